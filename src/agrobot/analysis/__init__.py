"""Study-specific analysis: metrics, paper comparisons and plots, called by the orchestrator."""
