"""Training runs: run directories, logs, the training loop and resuming."""
