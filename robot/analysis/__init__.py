"""Analyses of results: the paper study, work-precision and stability studies."""
