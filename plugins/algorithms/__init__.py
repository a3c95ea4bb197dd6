"""Built-in learning algorithms."""
