"""The ``pymotoros`` command line."""
