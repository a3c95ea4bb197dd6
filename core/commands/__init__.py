"""What command plugins share with the built-in CLI: the recipe flags and bounded number
flags. Public (in the plugin toolkit), so a third-party command parses ``--recipe``,
``--set`` and picture sizes exactly as ``retarget train`` does, without importing the CLI."""
