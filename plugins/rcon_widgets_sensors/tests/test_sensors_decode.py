"""Image decoding (every encoding), compressed images, laser scans and occupancy grids -> RGB pixels."""

import base64
import math

import cv2
import numpy as np
import pytest
from rcon_widgets_sensors.decode import (
    DecodeError,
    decode_compressed,
    decode_image,
    depth_to_rgb,
    message_kind,
)
from rcon_widgets_sensors.scan_render import HIT, render_grid, render_scan, ring_step


def scene(h=48, w=64):
    """Four flat colour quadrants (red, green, blue, white): demosaicing and colour order are checkable."""
    img = np.zeros((h, w, 3), np.uint8)
    img[: h // 2, : w // 2] = (220, 30, 30)
    img[: h // 2, w // 2:] = (30, 220, 30)
    img[h // 2:, : w // 2] = (30, 30, 220)
    img[h // 2:, w // 2:] = (240, 240, 240)
    return img


def image_msg(pix, encoding, step=None, data_as="bytes", bigendian=0):
    h, w = pix.shape[:2]
    raw = np.ascontiguousarray(pix).tobytes()
    row = len(raw) // h
    if step and step > row:
        raw = b"".join(raw[i * row:(i + 1) * row] + b"\0" * (step - row) for i in range(h))
    data = base64.b64encode(raw).decode() if data_as == "base64" else raw
    return {"header": {"stamp": {"secs": 1, "nsecs": 0}}, "height": h, "width": w, "encoding": encoding,
            "is_bigendian": bigendian, "step": step or row, "data": data}


def centre_colours(rgb):
    h, w = rgb.shape[:2]
    return [tuple(int(c) for c in rgb[y, x]) for y, x in ((h // 4, w // 4), (h // 4, 3 * w // 4),
                                                          (3 * h // 4, w // 4), (3 * h // 4, 3 * w // 4))]


def close(a, b, tol=12):
    return all(abs(x - y) <= tol for x, y in zip(a, b, strict=True))


EXPECTED = [(220, 30, 30), (30, 220, 30), (30, 30, 220), (240, 240, 240)]


@pytest.mark.parametrize("encoding,convert", [
    ("rgb8", None), ("bgr8", cv2.COLOR_RGB2BGR), ("rgba8", cv2.COLOR_RGB2RGBA), ("bgra8", cv2.COLOR_RGB2BGRA),
    ("8UC3", cv2.COLOR_RGB2BGR),
])
def test_colour_encodings_keep_colours(encoding, convert):
    pix = scene() if convert is None else cv2.cvtColor(scene(), convert)
    rgb = decode_image(image_msg(pix, encoding))
    assert rgb.shape == (48, 64, 3) and rgb.dtype == np.uint8 and rgb.flags.c_contiguous
    assert centre_colours(rgb) == EXPECTED


def test_padded_rows_and_base64_data():
    rgb = decode_image(image_msg(scene(), "rgb8", step=64 * 3 + 16, data_as="base64"))
    assert centre_colours(rgb) == EXPECTED


@pytest.mark.parametrize("encoding,bayer_offsets", [
    ("bayer_rggb8", ((0, 0, 0), (0, 1, 1), (1, 0, 1), (1, 1, 2))),
    ("bayer_bggr8", ((0, 0, 2), (0, 1, 1), (1, 0, 1), (1, 1, 0))),
    ("bayer_gbrg8", ((0, 0, 1), (0, 1, 2), (1, 0, 0), (1, 1, 1))),
    ("bayer_grbg8", ((0, 0, 1), (0, 1, 0), (1, 0, 2), (1, 1, 1))),
])
def test_bayer_patterns_demosaic_to_the_right_colours(encoding, bayer_offsets):
    src = scene()
    mosaic = np.zeros(src.shape[:2], np.uint8)
    for dy, dx, ch in bayer_offsets:
        mosaic[dy::2, dx::2] = src[dy::2, dx::2, ch]
    rgb = decode_image(image_msg(mosaic, encoding))
    for got, want in zip(centre_colours(rgb), EXPECTED, strict=True):
        assert close(got, want, 20), (encoding, got, want)


def test_mono_encodings():
    gray = np.tile(np.arange(64, dtype=np.uint8) * 4, (8, 1))
    rgb = decode_image(image_msg(gray, "mono8"))
    assert tuple(rgb[0, 10]) == (40, 40, 40)
    g16 = gray.astype(np.uint16) * 257
    for big in (0, 1):
        pix = g16.byteswap() if big else g16
        rgb16 = decode_image(image_msg(pix, "mono16", bigendian=big))
        assert tuple(rgb16[0, 10]) == (40, 40, 40)


def test_depth_16uc1_and_32fc1_false_colour_with_holes_black():
    depth = np.tile(np.linspace(500, 5000, 64).astype(np.uint16), (8, 1))
    depth[:, :4] = 0  # no reading
    rgb = decode_image(image_msg(depth, "16UC1"), depth_range=(500, 5000))
    assert tuple(rgb[0, 0]) == (0, 0, 0)
    near, far = rgb[0, 5].astype(int), rgb[0, 63].astype(int)
    assert np.abs(near - far).sum() > 100  # the colour map spans the range
    f = (depth.astype(np.float32) / 1000)
    f[0, 10] = np.nan
    f[1, 10] = np.inf
    rgb32 = decode_image(image_msg(f, "32FC1"))  # automatic range
    assert tuple(rgb32[0, 10]) == (0, 0, 0) and tuple(rgb32[1, 10]) == (0, 0, 0)
    assert rgb32[2, 30].sum() > 0
    assert depth_to_rgb(np.zeros((2, 2), np.float32)).sum() == 0


def test_yuv422():
    # BT.601 video-range Y'CbCr, as cameras send it
    f = scene().astype(np.float64) / 255
    r, g, b = f[..., 0], f[..., 1], f[..., 2]
    y = 16 + 65.481 * r + 128.553 * g + 24.966 * b
    cb = 128 - 37.797 * r - 74.203 * g + 112.0 * b
    cr = 128 + 112.0 * r - 93.786 * g - 18.214 * b
    uyvy = np.zeros((48, 64, 2), np.uint8)
    uyvy[:, :, 1] = np.round(y)
    uyvy[:, 0::2, 0] = np.round(cb[:, 0::2])
    uyvy[:, 1::2, 0] = np.round(cr[:, 0::2])
    yuy2 = uyvy[:, :, ::-1].copy()  # YUYV: luma first
    for enc, pix in (("yuv422", uyvy), ("yuv422_yuy2", yuy2)):
        rgb = decode_image(image_msg(pix, enc))
        for got, want in zip(centre_colours(rgb), EXPECTED, strict=True):
            assert close(got, want, 25), (enc, got, want)


def test_bad_images_give_clear_errors():
    with pytest.raises(DecodeError, match="encoding 'hsv8' is not supported"):
        decode_image(image_msg(scene(), "hsv8"))
    short = image_msg(scene(), "rgb8")
    short["data"] = short["data"][:100]
    with pytest.raises(DecodeError, match="expected step x height"):
        decode_image(short)
    bad_step = image_msg(scene(), "rgb8")
    bad_step["step"] = 10
    with pytest.raises(DecodeError, match="step 10 is less than"):
        decode_image(bad_step)
    with pytest.raises(DecodeError, match="not base64"):
        decode_image({**image_msg(scene(), "rgb8"), "data": "***"})
    with pytest.raises(DecodeError, match="empty image"):
        decode_image({**image_msg(scene(), "rgb8"), "width": 0})


def test_compressed_jpeg_png_and_depth_png():
    src = scene()
    ok, jpg = cv2.imencode(".jpg", cv2.cvtColor(src, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 95])
    rgb = decode_compressed({"format": "jpeg", "data": jpg.tobytes()})
    for got, want in zip(centre_colours(rgb), EXPECTED, strict=True):
        assert close(got, want), (got, want)
    ok, png = cv2.imencode(".png", cv2.cvtColor(src, cv2.COLOR_RGB2BGR))
    assert centre_colours(decode_compressed({"format": "png", "data": base64.b64encode(png.tobytes()).decode()})) \
        == EXPECTED
    depth = np.tile(np.linspace(500, 5000, 64).astype(np.uint16), (8, 1))
    ok, dpng = cv2.imencode(".png", depth)
    header = b"\0" * 12  # compressedDepth's config header
    rgb = decode_compressed({"format": "16UC1; compressedDepth png", "data": header + dpng.tobytes()})
    assert rgb.shape == (8, 64, 3) and rgb[0, 5].sum() > 0
    with pytest.raises(DecodeError, match="could not decode the JPEG"):
        decode_compressed({"format": "jpeg", "data": b"\xff\xd8\xff" + b"garbage" * 10})
    with pytest.raises(DecodeError, match="no data"):
        decode_compressed({"format": "jpeg", "data": ""})


def scan(ranges, rmin=0.2, rmax=10.0):
    n = len(ranges)
    return {"angle_min": -math.pi / 2, "angle_max": math.pi / 2, "angle_increment": math.pi / max(1, n - 1),
            "range_min": rmin, "range_max": rmax, "ranges": ranges, "intensities": []}


def test_scan_counts_and_drawing_handle_nan_null_inf_and_out_of_range():
    ranges = [5.0] * 10 + [None] * 3 + [float("nan")] * 2 + [float("inf"), 0.05, 42.0]
    img, counts = render_scan(scan(ranges), size=200)
    assert (counts.valid, counts.invalid, counts.out_of_range) == (10, 5, 3)
    assert img.shape == (200, 200, 3)
    hits = np.all(img == np.array(HIT, np.uint8), axis=2)
    assert hits.sum() > 10  # the valid returns are drawn


def test_scan_points_land_where_the_geometry_says():
    # one return straight ahead at 5 m with range_max 10: drawn half way up from the centre
    msg = {"angle_min": 0.0, "angle_max": 0.0, "angle_increment": 0.01, "range_min": 0.1, "range_max": 10.0,
           "ranges": [5.0]}
    img, _ = render_scan(msg, size=200)
    hits = np.argwhere(np.all(img == np.array(HIT, np.uint8), axis=2))
    cy, cx = hits.mean(axis=0)
    assert abs(cx - 100) < 3 and abs(cy - (100 - 5 * (96 / 10))) < 3


def test_ring_step_is_round():
    assert ring_step(10) == 5 and ring_step(30) == 10 and ring_step(3.5) == 1 and ring_step(0.4) == 0.1


def test_grid_colours_and_orientation():
    # 3 x 2 grid: bottom row (row 0 = south) unknown, free, occupied; top row 50% everywhere
    msg = {"info": {"width": 3, "height": 2, "resolution": 0.5}, "data": [-1, 0, 100, 50, 50, 50]}
    rgb = render_grid(msg)
    assert rgb.shape == (2, 3, 3)
    assert tuple(rgb[1, 0]) == (128, 134, 145)  # unknown, drawn on the bottom row
    assert tuple(rgb[1, 1]) == (255, 255, 255) and tuple(rgb[1, 2]) == (0, 0, 0)
    assert 120 <= rgb[0, 0, 0] <= 130
    with pytest.raises(DecodeError, match="expected width x height = 6"):
        render_grid({"info": {"width": 3, "height": 2, "resolution": 1}, "data": [0]})


def test_message_kind_reads_the_fields():
    assert message_kind(image_msg(scene(), "rgb8")) == "image"
    assert message_kind({"format": "jpeg", "data": b""}) == "compressed"
    assert message_kind(scan([1.0])) == "scan"
    assert message_kind({"info": {"resolution": 1}, "data": []}) == "grid"
    assert message_kind({"data": 1.0}) == ""
