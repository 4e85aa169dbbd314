"""Models shared by several components (equations of the paper, no co-simulation plumbing)."""
