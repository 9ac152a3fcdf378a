"""Orchestration of many replays: ``batch`` (logs × seeds × parameters, on Ray when installed) and
``bench`` (replay against read+decode), ``evaluate`` (trackers on a labelled corpus: ``corpus``
manifest, ``case_logs`` recording and marking, ``scenes``, the ``csrt`` baseline, ``evaluate_report``);
``notebook``: the Python API's ``evaluate`` and ``smooth``.

May import: everything below it (``replay.log``, ``core``, ``views``, ``analysis``), ``schemas``,
``trackers``, ``recorder``, itself.
"""
