"""Building characters: the procedural MJCF builder, joint maps and kinematic retargeting.

``builder`` and ``joint_map`` are toolkit modules a third-party character uses (see
:mod:`retarget.testing.toolkit`); ``kinematic`` turns a human clip into a character reference.
"""
