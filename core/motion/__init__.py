"""Human motion: the canonical skeleton, clips, readers' shared math, devices and the library.

Import the submodules directly (``from retarget.motion.clip import MotionClip``); this package
keeps its import light so that plugins can depend on it without pulling in the simulator.
"""
