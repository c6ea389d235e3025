"""The map view built and rendered through RCON's view test harness (rcon_core.testing): a fix from the
state is drawn (the image differs from the view without one)."""

from rcon_widgets_map.model import MapModel
from rcon_widgets_map.settings import MapPluginSettings, MapSettings
from rcon_widgets_map.view import MapView

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding
from rcon_core.sim import Vessel
from rcon_core.testing import RecordingPort, grab_view

TYPES = TypeRegistry.standard()


def test_map_view_through_the_harness(qapp, tmp_path):
    model = MapModel(MapSettings(), Binding("/gps/fix", "sensor_msgs/NavSatFix", "subscribe"), RecordingPort(),
                     types=TYPES, plugin_settings=MapPluginSettings())
    empty = grab_view(MapView, model, size=(320, 240))
    fix = TYPES.default("sensor_msgs/NavSatFix")
    fix.update(latitude=Vessel().origin_lat, longitude=Vessel().origin_lon)
    model.on_message(fix)
    assert model.state.count == 1
    image = grab_view(MapView, model, size=(320, 240), path=tmp_path / "map.png")
    assert (tmp_path / "map.png").stat().st_size > 0
    assert image.size() == empty.size() and image != empty  # the fix is drawn
