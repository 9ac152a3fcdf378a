"""Rerun: the sink (file and live), the parts every view is drawn from, each tracker's view, and
``overlay`` (a trajectory drawn over the log's pictures).

A tracker's spec names its view by dotted module (``TrackerSpec.view``, e.g.
``"trackreplay.replay.views.golf"``: trackers do not import views); the registry imports it. A view
is anything with ``blueprint(name)`` and ``log(rec, name, frame, intermediates, states)``.

May import: ``schemas``, ``trackers``, ``recorder`` (atomic writes), itself. Nothing of the replay
engine: a view draws what it is handed.
"""
