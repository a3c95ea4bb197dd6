"""Building scenes: the floor, the prop-scene base class that most scenes derive from, and the
contact links that scene-contact rewards and metrics share. Toolkit modules for scene plugins."""
