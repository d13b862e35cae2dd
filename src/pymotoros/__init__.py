"""pymotoros: a virtual Yaskawa Motoman controller running MotoROS, and a client for real robots.

The virtual controller speaks the ROS-Industrial Simple Message protocol exactly as
MotoROS 1.9.12 does (motion port 50240, state 50241, IO 50242); the client drives a
real controller and the twin the same way.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("pymotoros")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0"

__all__ = ["__version__"]
