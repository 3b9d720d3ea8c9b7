"""The multi-target tracker: predict, gate, assign, update, life cycle."""
