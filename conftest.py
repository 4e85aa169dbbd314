"""Puts the repository root on sys.path so tests can name their own toy components, and gives the
tests the command line as one fixture (``cli``: tests/commands.py)."""
import os

import pytest


@pytest.fixture
def cli():
    """``cli("run", study, "--out", out)``: ``python -m agrobot`` from the repository root."""
    from tests.commands import cli as run_cli

    return run_cli


@pytest.fixture(autouse=True)
def environment_as_before():
    """The environment as it was before the test (a sweep run in the test process sets its BLAS
    thread variables and keeps them): each test starts from the same one, and ``cli`` keeps forking
    its commands from the interpreter it started (tests/commands.py; a changed environment runs the
    real ``python -m agrobot``, 1.5 CPU s a command)."""
    before = dict(os.environ)
    yield
    if dict(os.environ) != before:
        os.environ.clear()
        os.environ.update(before)


@pytest.fixture(scope="session", autouse=True)
def diagnoses_fit_on_their_share_of_the_cores():
    """Under xdist, a diagnosis run in a test process fits its candidates on that process's share of
    the cores (its default is every core: on two cores, two test processes each fitting ahead on two
    workers spend CPU on fits the selection never asks for). The result is the same whatever the number
    (tests/test_diagnosis_workers.py, which sets it); commands forked through ``cli`` keep the default."""
    count = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    if count < 2:
        yield
        return
    from agrobot.diagnosis import parallel_fits, pipeline

    share = max(1, parallel_fits.default_workers() // count)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(pipeline, "default_workers", lambda: share)
        yield


# The long scenarios: a test that uses one of these module fixtures (a full-length study, a batch of
# diagnoses, a compiled set of FMUs) is in the slow tier; the fast tier is pytest -m "not slow".
SLOW_FIXTURES = {
    "test_diagnosis.py": {"hidden"},                    # 20 generated logs diagnosed
    "test_diagnosis_open_world.py": {"runs"},
    "test_diagnosis_specificity.py": {"runs"},
    "test_diagnosis_real_vehicles.py": {"ds1"},
    "test_verdicts_truths.py": {"runs"},                # six truths diagnosed
    "test_identify_driving.py": {"ds5"},                # a real log identified by the driving method
    "test_identification.py": {"study_run"},            # the paper's section IV experiment, every speed
    "test_figure8_closed_loop.py": {"cli_run"},         # the 160 s figure-8 through the command
    "test_foreign_engines.py": {"figure8_ssp"},         # the figure-8 as SSP in other engines
    "test_component_fmus.py": {"component_fmus"},       # every component compiled as an FMU
    "test_fmu_export_standard.py": {"exported"},
}


SLOW_TIMEOUT_S = 1200       # a slow test's limit (pytest-timeout; the others have pyproject's timeout = 300)


def pytest_configure(config):
    config.pluginmanager.register(LongestFilesFirst(), "agrobot-longest-files-first")


def pytest_collection_modifyitems(config, items):
    for item in items:
        heavy = SLOW_FIXTURES.get(item.path.name, set())
        if heavy & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)
        if item.get_closest_marker("slow") is not None and item.get_closest_marker("timeout") is None:
            item.add_marker(pytest.mark.timeout(SLOW_TIMEOUT_S))


# CPU seconds per test (set AGROBOT_TEST_CPU=FILE): each phase's process CPU time, children included
# (a command the test starts), appended as "nodeid<TAB>phase<TAB>seconds" lines; wall time misleads on
# a shared machine, CPU time does not
_CPU_LOG = os.environ.get("AGROBOT_TEST_CPU")


def _cpu_seconds():
    import sys

    t = os.times()
    forked = getattr(sys.modules.get("tests.commands"), "forked_cpu_seconds", 0.0)    # tests/commands.py's
    return t.user + t.system + t.children_user + t.children_system + forked


if _CPU_LOG:
    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_setup(item):
        yield from _record_cpu(item, "setup")

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_call(item):
        yield from _record_cpu(item, "call")

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_teardown(item):
        yield from _record_cpu(item, "teardown")


def _record_cpu(item, phase):
    start = _cpu_seconds()
    yield
    with open(_CPU_LOG, "a") as log:
        log.write(f"{item.nodeid}\t{phase}\t{_cpu_seconds() - start:.3f}\n")


# The files that cost most, in seconds: its fast tests' (CPU, AGROBOT_TEST_CPU with -n 0), its slow
# tests' (the whole suite's --durations on two nearly idle cores; approximate, enough to order them).
# With one xdist worker per file (--dist loadfile, and
# --no-loadscope-reorder to keep this order instead of xdist's most-tests-first), a long file started
# last holds one core while the others idle: these go first, the longest first.
FILE_CPU_S = {
    "test_diagnosis_real_vehicles.py": (3, 150),
    "test_diagnosis_open_world.py": (3, 125),
    "test_diagnosis_specificity.py": (1, 105),
    "test_partial_logs_and_vehicles.py": (5, 90),
    "test_verdicts_truths.py": (12, 75),
    "test_steering_map_causes.py": (1, 63),
    "test_field_missions.py": (15, 62),
    "test_hardware_io.py": (1, 75),
    "test_reader_abuse.py": (5, 62),
    "test_whole_field.py": (10, 50),
    "test_field_recordings.py": (16, 35),
    "test_diagnosis.py": (1, 35),
    "test_tree.py": (1, 36),
    "test_reliability.py": (4, 17),
    "test_live_viewers.py": (6, 30),
    "test_ground.py": (9, 10),
    "test_real_recordings.py": (7, 20),
    "test_install.py": (1, 20),
    "test_diagnosis_split.py": (3, 17),
    "test_foreign_engines.py": (7, 10),
    "test_python_api.py": (2, 15),
    "test_result_doors.py": (3, 13),
    "test_margins.py": (19, 21),
    "test_other_data.py": (3, 12),
    "test_fmu.py": (11, 1),
    "test_identify_driving.py": (1, 10),
    "test_steering_gain.py": (1, 10),
    "test_heading_measures_yaw.py": (3, 10),
    "test_fuzz_readers.py": (9, 1),
}


class LongestFilesFirst:
    """Orders the selected tests' files by FILE_CPU_S, after -m has deselected (a file's slow cost
    counts only where its slow tests run); the tests inside a file keep their order."""

    @pytest.hookimpl(trylast=True)
    def pytest_collection_modifyitems(self, config, items):
        slow_files = {i.path.name for i in items if i.get_closest_marker("slow") is not None}

        def cost(item):
            fast, slow = FILE_CPU_S.get(item.path.name, (0.0, 0.0))
            return -(fast + (slow if item.path.name in slow_files else 0.0))

        items.sort(key=cost)
