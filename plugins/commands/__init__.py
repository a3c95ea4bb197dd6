"""Built-in extra ``retarget`` subcommands contributed through the plugin API."""
