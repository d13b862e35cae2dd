"""The one exception tree of pymotoros.

::

    PymotorosError
     +-- ProtocolError                  (abstract)
     |    +-- LocalProtocolError        we tried to build or send something illegal
     |    +-- RemoteProtocolError       the peer sent bytes we cannot accept
     +-- ConfigError                    a cell file, model name or option is wrong (ValueError)
     |    +-- PathBlockedError          no collision-free path around the cell's obstacles
     +-- JobError                       an INFORM job cannot be loaded (ValueError)
     +-- TrajectoryRejectedError        the offline engine refuses a point as MotoROS would
     +-- KinematicsError                a pose no joint values reach (ValueError)
     +-- RecordingError                 (pymotoros.client.recording, ValueError) a bad pcapng file
     +-- PflRefusedError                (pymotoros.controller.safety, ValueError) a PFL event
     |                                  the cell cannot produce now
     +-- ClientError                    (pymotoros.client.errors: connection, reply, IO errors…)
          +-- PlanningError             (ValueError) a move cannot be planned
          +-- NamedPoseError            (ValueError) an SRDF or a named pose is wrong

Expected refusals of the virtual controller (NOT_READY, INVALID …) are *values*
returned by the domain, not exceptions; these classes are for what must stop the
caller. Exceptions also inherit the matching builtin (``ValueError`` …) so plain
``except ValueError`` keeps working. The classes users catch are importable from the
front door (``pymotoros.PlanningError`` …); ``tests/test_front_door.py`` checks that
each exception exported there derives from :class:`PymotorosError`, and
``tests/test_errors.py`` that every public exception class of the package does.
"""

from __future__ import annotations


class PymotorosError(Exception):
    """Root of every exception raised on purpose by pymotoros."""


class ProtocolError(PymotorosError):
    """Bytes and messages that break the Simple Message rules. Abstract: use a subclass."""

    def __new__(cls, *args: object, **kwargs: object) -> ProtocolError:
        if cls is ProtocolError:
            raise TypeError("ProtocolError is abstract; raise Local- or RemoteProtocolError")
        return super().__new__(cls, *args, **kwargs)


class LocalProtocolError(ProtocolError, ValueError):
    """We were asked to build or send a message that is not legal on the wire."""


class RemoteProtocolError(ProtocolError):
    """The peer sent something we cannot decode (bad length, short body, bad value)."""

    def __init__(self, message: str, *, data: bytes = b"") -> None:
        super().__init__(message)
        self.data = data
        """The offending bytes (possibly truncated), for logs and bug reports."""


class ConfigError(PymotorosError, ValueError):
    """A cell configuration, model name or command-line option is wrong.

    The message names the key (``groups[0].robot``) and says what is wrong with it.
    """


class PathBlockedError(ConfigError):
    """No collision-free path around the cell's obstacles (``plan --avoid``, ``move
    --avoid``, ``move_joints(..., avoid=True)``): a waypoint in collision, or a goal the
    planner cannot reach. The message names the obstacle in the way."""


class JobError(PymotorosError, ValueError):
    """An INFORM job cannot be loaded; the message names the file and line."""


class TrajectoryRejectedError(PymotorosError, ValueError):
    """A trajectory point MotoROS would refuse (offline engine, ``pymotoros interpolate``).

    Carries the point index, the axis, the offending value, the limit and the subcode.
    """

    def __init__(
        self,
        message: str,
        *,
        point: int,
        subcode: int,
        axis: int | None = None,
        value: float | None = None,
        limit: float | None = None,
    ) -> None:
        super().__init__(message)
        self.point = point
        self.subcode = subcode
        self.axis = axis
        self.value = value
        self.limit = limit


class KinematicsError(PymotorosError, ValueError):
    """A pose no joint values reach (out of reach, at a singularity, outside a joint limit),
    or a group without a kinematic chain. The message says which and by how much."""
