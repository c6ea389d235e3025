# The embedded simulated robot's fixtures (sim, sim_thread, sim_url) come from RCON itself.
pytest_plugins = ["rcon_core.testing"]
