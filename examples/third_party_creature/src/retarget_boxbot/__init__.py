"""Example third-party plugins for retarget: the ``boxbot`` character and the
``head_velocity`` sensor, written against the public API and the toolkit only."""
