"""Enable the pymotoros pytest plugin: the ``pymotoros_twin`` fixture."""

pytest_plugins = ["pymotoros.pytest_plugin"]
