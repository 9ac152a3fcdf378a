"""Reading a log: CRC-checked chunks in total order, image decoding, frame bundles, read-ahead,
the marks that start a tracker, the ground truth a log carries, and ``info``'s report.

May import: ``schemas``, ``trackers`` (``Frame``), ``recorder`` (the shared record walker), itself.
"""
