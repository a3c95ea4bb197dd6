"""``retarget character ...``: look at characters and at kinematic retargeting."""
