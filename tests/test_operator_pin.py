"""The operator PIN is kept as a salted scrypt hash: never the PIN, different each time, damaged records
never match, and PINs that are not 4 to 20 digits are refused with the reason."""

import pytest

from rcon_core.app.config import AppConfig
from rcon_core.app.pin import check_pin, make_record, pin_problem


def shows_pin(stored: object, pin: str) -> bool:
    """Whether ``stored`` (a JSON value) holds ``pin`` readably: as a value, or inside text that is not hex
    (a salt or hash is random hex and holds any four digits now and then: 1 run in about 600)."""
    if isinstance(stored, dict):
        return any(shows_pin(k, pin) or shows_pin(v, pin) for k, v in stored.items())
    if isinstance(stored, list):
        return any(shows_pin(v, pin) for v in stored)
    text = str(stored)
    if text == pin:
        return True
    return pin in text and not all(c in "0123456789abcdef" for c in text.lower())


def test_a_pin_is_stored_salted_and_hashed_and_checked():
    a, b = make_record("2468"), make_record("2468")
    assert a["salt"] != b["salt"] and a["hash"] != b["hash"]  # a fresh salt each time
    assert not shows_pin(a, "2468") and shows_pin({"x": "pin 2468"}, "2468") and shows_pin([2468], "2468")
    assert check_pin(a, "2468") and check_pin(b, "2468")
    assert not check_pin(a, "2469") and not check_pin(a, "")


@pytest.mark.parametrize("record", [
    None, {}, {"kdf": "md5"}, {"kdf": "scrypt", "n": 16384, "r": 8, "p": 1, "salt": "zz", "hash": "00"},
    {"kdf": "scrypt", "n": 2**40, "r": 8, "p": 1, "salt": "00", "hash": "00"}, "scrypt",
])
def test_a_damaged_record_never_matches(record):
    assert check_pin(record, "2468") is False


@pytest.mark.parametrize("pin, problem", [
    ("123", "4 to 20 digits"), ("1" * 21, "4 to 20 digits"), ("12a4", "digits only"),
    ("١٢٣٤", "digits only"), ("", "digits only"),
])
def test_bad_pins_are_refused_with_the_reason(pin, problem):
    assert problem in pin_problem(pin)
    with pytest.raises(ValueError, match=problem):
        make_record(pin)


def test_the_config_keeps_the_pin_record_and_view_only_robots(tmp_path):
    config = AppConfig(tmp_path)
    assert config.pin_record is None and not config.is_view_only("ws://robot:9090")
    config.set_pin_record(make_record("97531"))
    config.set_view_only("ws://robot:9090", True)
    again = AppConfig(tmp_path)
    assert check_pin(again.pin_record, "97531") and again.is_view_only("ws://robot:9090")
    again.set_view_only("ws://robot:9090", False)
    again.set_pin_record(None)
    last = AppConfig(tmp_path)
    assert last.pin_record is None and not last.is_view_only("ws://robot:9090")
