"""Entry point of this widget package (group `rcon.widgets`): the module the plugin manager registers.

It must import without Qt: views are referenced lazily as `module:attr` strings.
"""

from rcon_core.plugins import Accepts, Role, WidgetSpec, hookimpl

#: the widget API this package is written against (rcon_core.plugins.api.API_VERSION when it was written)
API = "1.1"

GPS_MAP = WidgetSpec(
    kind="map.gps",
    title="GPS Map",
    icon="map",
    description="The robot's GPS fix on a map (offline MBTiles, online tiles or a plain grid) with its trail, "
                "heading and accuracy; tap to send a goal fix",
    category="Navigation",
    roles={Role.SUBSCRIBE, Role.PUBLISH},
    # NavSatFix exactly; anything else with numeric latitude/longitude (e.g. geographic_msgs/GeoPoint,
    # or a message holding one) structurally, bound to that (sub)message
    accepts=Accepts(types=["sensor_msgs/NavSatFix"], messages=["geo"]),
    settings="rcon_widgets_map.settings:MapSettings",
    plugin_settings="rcon_widgets_map.settings:MapPluginSettings",
    model="rcon_widgets_map.model:MapModel",
    view="rcon_widgets_map.view:MapView",
    default_size=(480, 400),
    priority=10,
    api_version=API,
)


@hookimpl
def rcon_register_widgets(registry):
    registry.add(GPS_MAP)
