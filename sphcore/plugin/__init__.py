"""The plugin system: hook specifications, the pluggy host, the run context handed to hooks."""
