"""Entry point of this widget package (group `rcon.widgets`): the module the plugin manager registers.

It must import without Qt: views are referenced lazily as `module:attr` strings.
"""
