"""pymotoros: a virtual Yaskawa Motoman controller running MotoROS, and a client for real robots.

The virtual controller speaks the ROS-Industrial Simple Message protocol exactly as
MotoROS 1.9.12 does (motion port 50240, state 50241, IO 50242); the client drives a
real controller and the twin the same way.
"""

from __future__ import annotations

__all__ = ["__version__"]


def __getattr__(name: str) -> str:
    # Looked up lazily: importlib.metadata imports socket (through email), and the
    # sans-I/O codec must be importable without loading any networking module.
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version("pymotoros")
        except PackageNotFoundError:  # a source tree that is not installed
            return "0.0.0"
    raise AttributeError(f"module 'pymotoros' has no attribute {name!r}")
