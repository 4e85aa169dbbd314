"""Model-discrepancy diagnosis: replay a measured log through the baseline model
subsystem by subsystem, test the catalogue of model extensions, name the one the evidence
supports and measure its gain on a held-out part of the log. Entry point: ``diagnose``."""
