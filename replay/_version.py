"""The camlog version: the one place it is written (``pyproject.toml`` reads it from here
when a wheel is built, so the installed metadata says the same). A constant rather than a
package-metadata lookup, which would cost every command that writes a log 30-40 ms of
``importlib.metadata`` start-up."""

VERSION = "0.1.0"
