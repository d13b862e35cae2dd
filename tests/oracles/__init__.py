"""Reference routes the library's one route is compared against, bit for bit.

Each hot rule of ``src/`` exists once, in its fast form. The plainer forms it replaced
live here, as independent oracles for the equality tests: they are never imported by
the library, so a change to a rule is made once in ``src/`` and checked here.

- :mod:`.interpolation`: every queued segment computed at once by the numpy kernels;
- :mod:`.trajectory`: JOINT_TRAJ_PT_FULL answered through a Process, field by field;
- :mod:`.messages`: construction checked field by field;
- :mod:`.registers`: the S1CxG register outputs computed in every tick;
- :mod:`.state_cycle`: the state stream as tasks, its frames packed one by one.
"""
