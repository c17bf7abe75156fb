"""Batch runs: pipelines of steps over many logs, in parallel processes or on Ray."""
