"""Puts the repository root on sys.path so tests can name their own toy components, and gives the
tests the command line as one fixture (``cli``: tests/commands.py)."""
import os
import sys

import pytest

# Bytecode is kept beside the sources (Python's default; __pycache__ is in .gitignore) even where the
# environment sets PYTHONDONTWRITEBYTECODE: without it each test process rewrites every test module's
# asserts again (7 CPU s of an xdist worker's collection) and every interpreter a test starts (a
# command, a sweep's workers, a forkserver) compiles agrobot again (0.7 CPU s each). Those interpreters
# keep the variable and read what the test processes wrote; no result depends on it.
sys.dont_write_bytecode = False


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


@pytest.fixture(autouse=True)
def progress_shown_as_before():
    """Progress lines as they were before the test: a command called in the test process
    (tests/commands.py's ``in_process``) with --no-progress or --quiet turns them off for the whole
    process (orchestrator.observers.PROGRESS), and a later test on the same worker that reads them
    (tests/test_runs_on_screen.py) would see none, depending on which files xdist gave that worker."""
    from agrobot.orchestrator.observers import PROGRESS

    before = dict(PROGRESS)
    yield
    PROGRESS.clear()
    PROGRESS.update(before)


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


# The files that cost most, in CPU seconds: (its fast tests', its slow tests'), each the sum over its tests
# of AGROBOT_TEST_CPU's phases (the fast tier under -n 2, slow tests under -n 0 or in the whole suite; the fast
# figures and the slow ones of the five files last listed from runs on a loaded machine, x 0.77: the idle fast
# tier's user time over that run's CPU); a slow figure marked "earlier" is the whole suite's --durations on two
# nearly idle cores, not yet measured again
# (test_hardware_io's and test_live_viewers' are real-time runs: their wall time is what holds a worker).
# With one xdist worker per file (--dist loadfile, and
# --no-loadscope-reorder to keep this order instead of xdist's most-tests-first), a long file started
# last holds one core while the others idle: these go first, the longest first; a file not listed
# (under 3 s) follows in collection order.
FILE_CPU_S = {
    "test_diagnosis_open_world.py": (1, 136),
    "test_field_missions.py": (15, 115),
    "test_diagnosis_specificity.py": (0, 105),   # slow: earlier
    "test_partial_logs_and_vehicles.py": (13, 90),   # slow: earlier
    "test_diagnosis_real_vehicles.py": (2, 84),
    "test_hardware_io.py": (3, 75),   # slow: earlier
    "test_verdicts_truths.py": (1, 75),   # slow: earlier
    "test_steering_map_causes.py": (0, 63),   # slow: earlier
    "test_whole_field.py": (8, 54),
    "test_field_recordings.py": (15, 45),
    "test_tree.py": (3, 36),   # slow: earlier
    "test_diagnosis.py": (0, 35),   # slow: earlier
    "test_live_viewers.py": (4, 30),   # slow: earlier
    "test_margins.py": (10, 21),   # slow: earlier
    "test_real_recordings.py": (5, 20),   # slow: earlier
    "test_install.py": (0, 20),   # slow: earlier
    "test_diagnosis_split.py": (1, 17),   # slow: earlier
    "test_reliability.py": (3, 17),   # slow: earlier
    "test_other_data.py": (6, 12),   # slow: earlier
    "test_sweep_judged.py": (17, 0),
    "test_ground.py": (7, 10),   # slow: earlier
    "test_python_api.py": (3, 15),   # slow: earlier
    "test_result_doors.py": (2, 13),   # slow: earlier
    "test_reader_abuse.py": (4, 12),
    "test_heading_measures_yaw.py": (3, 10),   # slow: earlier
    "test_car_held_out.py": (6, 0),
    "test_identify_driving.py": (1, 10),   # slow: earlier
    "test_robust_guidance.py": (12, 0),
    "test_fmu.py": (10, 1),   # slow: earlier
    "test_foreign_engines.py": (1, 10),   # slow: earlier
    "test_fuzz_readers.py": (9, 1),   # slow: earlier
    "test_steering_gain.py": (0, 10),   # slow: earlier
    "test_hard_driving_diagnosis.py": (0, 10),
    "test_mcap_live.py": (9, 0),
    "test_two_doors.py": (8, 0),
    "test_compiled_cache.py": (9, 0),
    "test_study_class_limits.py": (5, 0),
    "test_diagnosis_workers.py": (3, 0),
    "test_sweep.py": (8, 0),
    "test_yaw_rate_mpc.py": (8, 0),
    "test_bounds_never_concluded.py": (5, 0),
    "test_lever_arm_outline_from_recording.py": (1, 0),
    "test_identify_withheld_values.py": (8, 0),
    "test_planner.py": (6, 0),
    "test_identify_turn_scale.py": (5, 7),
    "test_fmu_import_conformance.py": (5, 0),
    "test_runs_on_screen.py": (4, 0),
    "test_skid_steer.py": (5, 0),
    "test_figures.py": (4, 0),
    "test_reading_noise.py": (1, 0),
    "test_loop_fmu.py": (3, 0),
    "test_tune.py": (4, 0),
    "test_identify_hard_driving.py": (2, 9),
    "test_margins_models.py": (3, 0),
    "test_curved_swaths.py": (4, 0),
    "test_identify_k_bias.py": (5, 0),
    "test_identify_banked_turns.py": (7, 0),
    "test_compiled_engine.py": (3, 0),
    "test_identify_fitted_part.py": (9, 0),
    "test_own_components.py": (4, 0),
    "test_extras.py": (3, 0),
    "test_car_steering_map_estimates.py": (8, 0),
    "test_newcomer_run.py": (4, 0),
    "test_fuzz_inputs.py": (3, 0),
    "test_identify_report_fields.py": (3, 0),
    "test_kinematic_regime.py": (3, 0),
    "test_bad_inputs_commands.py": (3, 0),
    "test_tractor_yaw_plant.py": (3, 0),
    "test_numpy_channels.py": (3, 0),
    "test_axle_friction_understeer.py": (0, 5),
    "test_curve_or_saturation.py": (2, 10),
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
