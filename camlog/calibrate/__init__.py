"""Calibration of cameras from a log: detect, select, solve, write the evidence, report."""
