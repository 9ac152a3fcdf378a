"""Orchestration of many replays: ``batch`` (logs × seeds × parameters, on Ray when installed) and
``bench`` (replay against read+decode).

May import: everything below it (``replay.log``, ``core``, ``views``, ``analysis``), ``schemas``,
``trackers``, ``recorder``, itself.
"""
