"""Gait libraries: a grid of plans built on Ray by continuation (`gaitlib.build`), kept as
MCAP recordings with an SQLite index (`gaitlib.index`), inspected with
``gait-planner library list|show|export``."""
