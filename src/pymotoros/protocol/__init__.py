"""Simple Message as MotoROS speaks it: sans-I/O codec (bytes in, typed messages out)."""
