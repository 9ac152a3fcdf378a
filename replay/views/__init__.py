"""Per-tracker Rerun views: how a tracker's intermediates are drawn, and the default layout."""
