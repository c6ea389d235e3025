"""Web-Mercator maths (EPSG:3857 as used by XYZ/TMS tile servers), pure Python.

Coordinates:

* *world pixels* at a (possibly fractional) zoom ``z``: the whole world is a square of
  ``TILE_SIZE * 2**z`` pixels, x growing east from longitude -180, y growing south from latitude
  +85.0511 (the Mercator cut-off).
* *tiles* ``(z, x, y)`` in the XYZ ("slippy map") scheme: row 0 at the top (north). MBTiles stores rows
  in the TMS scheme (row 0 at the bottom); :func:`tms_row` converts (it is its own inverse).
"""

from __future__ import annotations

import math

TILE_SIZE = 256
#: latitude where the Mercator square ends (arctan(sinh(pi)))
MAX_LAT = math.degrees(math.atan(math.sinh(math.pi)))
#: WGS-84 equatorial radius, the sphere Web-Mercator uses
EARTH_RADIUS_M = 6_378_137.0
EARTH_CIRCUMFERENCE_M = 2 * math.pi * EARTH_RADIUS_M
MAX_ZOOM = 24


def clamp_lat(lat: float) -> float:
    """Latitude limited to what Web-Mercator can show."""
    return max(-MAX_LAT, min(MAX_LAT, lat))


def world_size(zoom: float) -> float:
    """Width (= height) of the world in pixels at ``zoom``."""
    return TILE_SIZE * 2.0**zoom


def latlon_to_world(lat: float, lon: float, zoom: float) -> tuple[float, float]:
    """Degrees -> world pixels at ``zoom`` (latitude clamped to the Mercator square)."""
    size = world_size(zoom)
    x = (lon + 180.0) / 360.0 * size
    s = math.sin(math.radians(clamp_lat(lat)))
    y = (0.5 - math.log((1 + s) / (1 - s)) / (4 * math.pi)) * size
    return x, y


def world_to_latlon(x: float, y: float, zoom: float) -> tuple[float, float]:
    """World pixels at ``zoom`` -> degrees. Longitude is not wrapped (x outside the world gives |lon| > 180)."""
    size = world_size(zoom)
    lon = x / size * 360.0 - 180.0
    n = math.pi * (1 - 2 * y / size)
    lat = math.degrees(math.atan(math.sinh(n)))
    return lat, lon


def tile_for(lat: float, lon: float, z: int) -> tuple[int, int]:
    """The XYZ tile ``(x, y)`` at zoom ``z`` holding the point (clamped to the world)."""
    x, y = latlon_to_world(lat, lon, z)
    n = 2**z
    return min(n - 1, max(0, int(x // TILE_SIZE))), min(n - 1, max(0, int(y // TILE_SIZE)))


def tile_bounds(z: int, x: int, y: int) -> tuple[float, float, float, float]:
    """``(north, west, south, east)`` in degrees of XYZ tile ``(z, x, y)``."""
    north, west = world_to_latlon(x * TILE_SIZE, y * TILE_SIZE, z)
    south, east = world_to_latlon((x + 1) * TILE_SIZE, (y + 1) * TILE_SIZE, z)
    return north, west, south, east


def tms_row(z: int, y: int) -> int:
    """XYZ row <-> TMS row (MBTiles ``tile_row``); the same formula both ways."""
    return (1 << z) - 1 - y


def wrap_tile_x(z: int, x: int) -> int:
    """Tile column wrapped around the antimeridian."""
    return x % (1 << z)


def valid_tile(z: int, x: int, y: int) -> bool:
    return 0 <= z <= MAX_ZOOM and 0 <= x < (1 << z) and 0 <= y < (1 << z)


def metres_per_pixel(lat: float, zoom: float) -> float:
    """Ground metres covered by one pixel at latitude ``lat`` and ``zoom``."""
    return EARTH_CIRCUMFERENCE_M * math.cos(math.radians(clamp_lat(lat))) / world_size(zoom)


def haversine_m(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    """Great-circle distance in metres (spherical Earth of radius :data:`EARTH_RADIUS_M`)."""
    p1, p2 = math.radians(lat1), math.radians(lat2)
    dp, dl = p2 - p1, math.radians(lon2 - lon1)
    a = math.sin(dp / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(dl / 2) ** 2
    return 2 * EARTH_RADIUS_M * math.asin(min(1.0, math.sqrt(a)))


def bearing_deg(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    """Initial compass bearing from point 1 to point 2, degrees clockwise from north in [0, 360)."""
    p1, p2 = math.radians(lat1), math.radians(lat2)
    dl = math.radians(lon2 - lon1)
    y = math.sin(dl) * math.cos(p2)
    x = math.cos(p1) * math.sin(p2) - math.sin(p1) * math.cos(p2) * math.cos(dl)
    return math.degrees(math.atan2(y, x)) % 360.0


def offset_m(lat: float, lon: float, east_m: float, north_m: float) -> tuple[float, float]:
    """The point ``east_m``/``north_m`` metres away (flat-Earth approximation, fine for < 10 km)."""
    dlat = math.degrees(north_m / EARTH_RADIUS_M)
    dlon = math.degrees(east_m / (EARTH_RADIUS_M * math.cos(math.radians(lat))))
    return lat + dlat, lon + dlon
