"""The test and benchmark harness, beside the package and not installed with it: the independent
truth tractor that draws 'measured' logs with hidden effects (truth_tractor), the runner that
diagnoses them with each effect's stated tolerances (hidden_effects), and small generated
recordings for the readers (generated_recordings). Tests import it from the repository root
(conftest.py puts the root on sys.path); benchmarks put the root on sys.path themselves."""
