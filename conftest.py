"""Puts the repository root on sys.path so tests can name their own toy components, and gives the
tests the command line as one fixture (``cli``: tests/commands.py)."""
import pytest


@pytest.fixture
def cli():
    """``cli("run", study, "--out", out)``: ``python -m agrobot`` from the repository root."""
    from tests.commands import cli as run_cli

    return run_cli


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


def pytest_collection_modifyitems(config, items):
    for item in items:
        heavy = SLOW_FIXTURES.get(item.path.name, set())
        if heavy & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)
        if item.get_closest_marker("slow") is not None and item.get_closest_marker("timeout") is None:
            item.add_marker(pytest.mark.timeout(SLOW_TIMEOUT_S))
