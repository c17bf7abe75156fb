"""The installed camlog version, read once from package metadata."""

from importlib.metadata import PackageNotFoundError, version

try:
    VERSION = version("camlog")
except PackageNotFoundError:  # running from a source tree that is not installed
    VERSION = "0.0.0+source"
