"""An example RCON widget package, the way a lab would write one (see docs/writing-a-widget-plugin.md)."""
