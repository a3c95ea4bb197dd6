"""Live: a headset stream in, the simulated avatar out, over a WebSocket (``retarget serve``)."""
