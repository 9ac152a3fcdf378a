"""Offline analysis with the whole log in hand: smoothing (RTS), the golf flight fit and the rescan
along it, scoring against ground truth (single-object metrics, CLEAR MOT / IDF1 / HOTA), and ``diff``.

May import: ``schemas``, ``trackers``, ``recorder``, ``replay.log``, ``replay.core``, ``replay.views``, itself.
"""
