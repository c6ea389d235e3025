"""RCON Map widget: GPS fixes on offline/online tile maps."""
