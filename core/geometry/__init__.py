"""Rotation maths in one place: numpy quaternions for motion data (``rotations``) and their
batched torch twins plus the character's heading frame for sensors and rewards (``heading``)."""
