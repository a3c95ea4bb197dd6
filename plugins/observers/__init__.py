"""Built-in observers: what the policy perceives of the scene around the character."""
