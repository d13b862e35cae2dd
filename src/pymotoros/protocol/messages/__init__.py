"""One immutable class per Simple Message body, exactly as MotoROS 1.9.12 lays it out.

Split by concern; ``from pymotoros.protocol.messages import X`` works for every
public name of every module below:

- :mod:`._base`: the :class:`Message` mixin (field checks, codec, registration),
  :class:`Role`, :class:`UnknownMessage`, the REQUEST_CLASSES / REPLY_CLASSES registry;
- :mod:`.motion`: PING, MOTO_MOTION_CTRL, MOTO_MOTION_REPLY, MOTO_SELECT_TOOL;
- :mod:`.trajectory`: JOINT_TRAJ_PT_FULL and JOINT_TRAJ_PT_FULL_EX;
- :mod:`.state`: ROBOT_STATUS, JOINT_FEEDBACK, JOINT_FEEDBACK_EX;
- :mod:`.io`: IO bits, groups, M-registers and the IO error reply;
- :mod:`.dh`: GET_DH_PARAMETERS.

Importing this package imports every module, and a class registers itself
when it is defined, so the decoders (built by ``framing`` from the registry)
know every message. A new message is one class in the module of its concern:
its public names are re-exported here through that module's ``__all__``.
"""

from pymotoros.protocol.messages import _base, dh, io, motion, state, trajectory
from pymotoros.protocol.messages._base import *  # noqa: F403
from pymotoros.protocol.messages.dh import *  # noqa: F403
from pymotoros.protocol.messages.io import *  # noqa: F403
from pymotoros.protocol.messages.motion import *  # noqa: F403
from pymotoros.protocol.messages.state import *  # noqa: F403
from pymotoros.protocol.messages.trajectory import *  # noqa: F403

__all__: list[str] = []
__all__ += _base.__all__
__all__ += dh.__all__
__all__ += io.__all__
__all__ += motion.__all__
__all__ += state.__all__
__all__ += trajectory.__all__
