"""A corpus of third-party calibration datasets: manifest, fetcher, OpenCV reference, runner."""
