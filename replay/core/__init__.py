"""The replay itself: the tracker registry (built from each tracker's declared spec), config loading,
the engine (``iter_steps`` → ``replay``), the digest, the trajectory table and its export, the
output writers and the Python API.

May import: ``schemas``, ``trackers``, ``recorder``, ``replay.log``, ``replay.views`` (the Rerun sink,
only when a replay writes an ``.rrd``), itself.
"""
