"""Built-in motion formats (readers of motion files onto the canonical skeleton)."""
