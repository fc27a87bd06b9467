"""Experiments: the paper's values, the run grid, summary tables and claims."""
