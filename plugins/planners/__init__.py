"""Built-in planners: tracking experts that need no training (``retarget expert``)."""
