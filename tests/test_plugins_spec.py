"""WidgetSpec / Accepts / Role validation, lazy references, settings, field paths."""

import attrs
import pytest

from rcon_core.plugins import Accepts, Role, SettingsError, SpecError, WidgetSpec, get_path, resolve, set_path
from rcon_core.plugins.paths import PathError, parse_path, split_service_path


@attrs.define
class RangeSettings:
    minimum: float = 0.0
    maximum: float = 1.0
    label: str = ""

    def problems(self) -> list[str]:
        return [] if self.minimum < self.maximum else ["the minimum must be below the maximum"]


def spec(**kw):
    base = dict(kind="t.range", title="Range", model="rcon_core.plugins.model:WidgetModel")
    base.update(kw)
    return WidgetSpec(**base)


def test_role_parse_accepts_names_and_rejects_junk():
    assert Role.parse("SUBSCRIBE") is Role.SUBSCRIBE
    assert Role.parse(Role.CALL) is Role.CALL
    assert Role.CALL.is_service and not Role.PUBLISH.is_service
    with pytest.raises(ValueError, match="unknown role 'listen'.*subscribe, publish, call, serve"):
        Role.parse("listen")


@pytest.mark.parametrize(
    "kw, message",
    [
        (dict(kind="Slider"), "dotted lowercase id"),
        (dict(kind="std"), "dotted lowercase id"),
        (dict(model="no_colon"), "package.module:attr"),
        (dict(view=object), "must be a 'module:attr' string"),
        (dict(roles=[]), "declares no role"),
        (dict(roles=["watch"]), "unknown role"),
    ],
)
def test_bad_specs_are_refused_with_a_reason(kw, message):
    with pytest.raises((SpecError, ValueError), match=message):
        spec(**kw)


def test_unknown_predicate_names_are_refused():
    with pytest.raises(SpecError, match="unknown field predicate 'numerc'.*numeric"):
        Accepts(fields=["numerc"])
    with pytest.raises(SpecError, match="unknown message predicate"):
        Accepts(messages=["picture"])
    with pytest.raises(SpecError, match="service_parts"):
        Accepts(service_parts=["reply"])
    custom = Accepts(fields=[lambda f: f.name == "x"], messages="image")
    assert custom.messages == ("image",)
    assert custom.describe()[-1] == "message:image"


def test_accepts_generic_flag_and_describe():
    assert Accepts(messages=["any"]).is_generic
    assert not Accepts(messages=["any"], fields=["numeric"]).is_generic
    d = Accepts(types=["std_msgs/Float64"], packages=["sensor_msgs"], fields=["numeric"]).describe()
    assert d == ["std_msgs/Float64", "sensor_msgs/*", "field:numeric"]
    # one spelling in listings, whichever the plugin declared
    assert Accepts(types=["geometry_msgs/msg/Twist", "std_msgs/Bool"]).describe() == [
        "geometry_msgs/Twist", "std_msgs/Bool"]


def test_view_is_lazy_and_missing_modules_are_named():
    s = spec(view="rcon_no_such_module.view:View")
    with pytest.raises(SpecError, match="cannot import 'rcon_no_such_module.view'"):
        s.load_view()
    with pytest.raises(SpecError, match="has no attribute 'Nope'"):
        resolve("rcon_core.plugins.model:Nope")
    assert spec(view=None).view is None
    with pytest.raises(SpecError, match="has no view"):
        spec().load_view()
    assert spec().load_model().__name__ == "WidgetModel"


def test_settings_structured_validated_and_round_tripped():
    s = spec(settings=RangeSettings)
    obj = s.make_settings({"minimum": 2, "maximum": 5, "unknown_key": True})
    assert obj == RangeSettings(2.0, 5.0, "")
    assert s.settings_to_dict(obj) == {"minimum": 2.0, "maximum": 5.0, "label": ""}
    assert s.settings_problems({"minimum": 3, "maximum": 1}) == ["the minimum must be below the maximum"]
    assert s.settings_problems({}) == []
    problems = s.settings_problems({"minimum": "low"})
    assert problems == ["invalid settings: minimum must be a number (got 'low')"]
    with pytest.raises(SettingsError):
        s.make_settings({"maximum": [1, 2]})
    assert spec().make_settings({"a": 1}) is None
    assert spec().settings_problems({"a": 1}) == []


def test_paths_get_set_and_errors():
    msg = {"pose": {"position": {"x": 1.5}}, "ranges": [0.1, 0.2, 0.3]}
    assert parse_path("pose.position.x") == ["pose", "position", "x"]
    assert parse_path("ranges[2]") == ["ranges", 2]
    assert get_path(msg, "ranges[1]") == 0.2
    assert get_path(msg, "") is msg
    with pytest.raises(PathError, match="'velocity' in 'pose' not found"):
        get_path(msg, "pose.velocity")
    for bad in ("a..b", ".a", "a.", "a[x]", "1a"):
        with pytest.raises(PathError, match="malformed"):
            parse_path(bad)
    out = set_path({}, "linear.x", 2.0)
    assert out == {"linear": {"x": 2.0}}
    with pytest.raises(PathError):
        set_path({}, "", 1)
    assert split_service_path("request.data") == ("request", "data")
    assert split_service_path("response") == ("response", "")
    with pytest.raises(PathError, match="must start with 'request' or 'response'"):
        split_service_path("data")
