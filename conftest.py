"""Puts the repository root on sys.path so tests can name their own toy components."""
