"""Golden-log regression: committed inputs, expected outputs, comparison with tolerances."""
