"""Type stubs of the compiled core. The public API wraps these; see the Python modules."""

__version__: str
