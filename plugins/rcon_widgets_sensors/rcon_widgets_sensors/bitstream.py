"""What a video packet is, read from its first bytes (pure Python, no PyAV, no Qt).

The Image widget decodes video only from a keyframe on (after a join, a lost packet or bad data), so it must
know a keyframe before the decoder sees it, whatever carried it: ``foxglove_msgs/CompressedVideo`` has no
flag for it, ``ffmpeg_image_transport_msgs/FFMPEGPacket`` has one (``flags`` bit 0) that is trusted.

* H.264 (Annex B): a packet with an IDR slice (NAL type 5) is a keyframe. The order of pictures is checked
  too: every reference picture's ``frame_num`` is one more than the previous one's (modulo
  ``MaxFrameNum`` from the sequence parameter set), so a lost reference picture shows as a jump
  (:class:`H264Order`). A lost picture nothing refers to is not seen, and needs not be: no later picture
  is drawn from it.
* H.265 (Annex B): a packet with an IRAP picture (NAL types 16-23) is a keyframe. Losses are not seen here.
* VP9: the uncompressed header's ``frame_type`` is 0 (a key frame).
* AV1: the packet carries a sequence header OBU (Foxglove's rule: every keyframe message carries one).

Only headers are read: a few dozen bytes per NAL unit (``bytes.find`` walks the start codes in C), so a
100 kB keyframe costs microseconds. Garbage never raises here: it is "no keyframe" (and the decoder, which
gets only what follows a keyframe, never sees it).
"""

from __future__ import annotations

__all__ = ["codec_of", "is_keyframe", "nal_units", "H264Order", "BitReader", "VIDEO_CODECS", "CODEC_TITLES"]

#: codec names as FFmpeg's decoders know them, by what a message may call them (lower case)
VIDEO_CODECS: dict[str, str] = {
    "h264": "h264", "avc": "h264", "avc1": "h264", "x264": "h264", "libx264": "h264", "h264_nvenc": "h264",
    "h264_vaapi": "h264", "h264_qsv": "h264", "h264_v4l2m2m": "h264", "h264_omx": "h264",
    "h264_videotoolbox": "h264",
    "h265": "hevc", "hevc": "hevc", "x265": "hevc", "libx265": "hevc", "hevc_nvenc": "hevc",
    "hevc_vaapi": "hevc", "hevc_qsv": "hevc", "hevc_videotoolbox": "hevc",
    "vp9": "vp9", "libvpx-vp9": "vp9", "vp9_vaapi": "vp9", "vp9_qsv": "vp9",
    "av1": "av1", "libaom-av1": "av1", "libsvtav1": "av1", "av1_nvenc": "av1", "av1_vaapi": "av1",
    "av1_qsv": "av1", "librav1e": "av1",
}
#: how the overlay names each codec
CODEC_TITLES = {"h264": "H.264", "hevc": "H.265", "vp9": "VP9", "av1": "AV1"}


def codec_of(name: str) -> str | None:
    """FFmpeg's decoder name for a ``format`` (CompressedVideo) or ``encoding`` (FFMPEGPacket: the codec
    or encoder's name, maybe followed by ``;pixel formats``); None when it names no video codec."""
    first = str(name).split(";", 1)[0].strip().lower()
    return VIDEO_CODECS.get(first)


def nal_units(data: bytes) -> list[tuple[int, int]]:
    """``(start, end)`` of each NAL unit's bytes (after its start code) in an Annex B byte stream."""
    out: list[tuple[int, int]] = []
    find = data.find
    i = find(b"\x00\x00\x01")
    while i >= 0:
        start = i + 3
        nxt = find(b"\x00\x00\x01", start)
        end = len(data) if nxt < 0 else nxt
        if nxt >= 0 and end > start and data[end - 1] == 0:  # a 4-byte start code's leading zero
            end -= 1
        if end > start:
            out.append((start, end))
        i = nxt
    return out


def _unescape(head: bytes) -> bytes:
    """A NAL unit's first bytes without emulation prevention (``00 00 03`` -> ``00 00``)."""
    return head.replace(b"\x00\x00\x03", b"\x00\x00") if b"\x00\x00\x03" in head else head


class BitReader:
    """Big-endian bits and Exp-Golomb codes from bytes; reading past the end raises ``EOFError``."""

    __slots__ = ("data", "pos")

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.pos = 0

    def u(self, n: int) -> int:
        value = 0
        for _ in range(n):
            byte = self.pos >> 3
            if byte >= len(self.data):
                raise EOFError("bitstream ends early")
            value = (value << 1) | ((self.data[byte] >> (7 - (self.pos & 7))) & 1)
            self.pos += 1
        return value

    def ue(self) -> int:
        zeros = 0
        while self.u(1) == 0:
            zeros += 1
            if zeros > 31:
                raise ValueError("Exp-Golomb code too long")
        return (1 << zeros) - 1 + self.u(zeros)

    def se(self) -> int:
        k = self.ue()
        return (k + 1) // 2 if k & 1 else -(k // 2)


#: H.264 profiles whose sequence parameter set carries chroma format and bit depths
_HIGH_PROFILES = frozenset({100, 110, 122, 244, 44, 83, 86, 118, 128, 138, 139, 134, 135})


def _skip_scaling_list(r: BitReader, size: int) -> None:
    last, nxt = 8, 8
    for _ in range(size):
        if nxt:
            nxt = (last + r.se() + 256) % 256
        last = nxt or last


class H264Order:
    """Follows an H.264 stream's ``frame_num`` to see lost reference pictures (see the module docstring).

    :meth:`check` takes each packet in order and says whether a picture is missing before it. It learns
    ``log2_max_frame_num`` from the stream's SPS (and which SPS from the PPS); until it has seen one, and
    for a stream that allows gaps in ``frame_num``, it never claims a loss.
    """

    def __init__(self) -> None:
        self._sps: dict[int, tuple[int, bool, bool]] = {}  # id -> (log2 max frame_num, separate planes, gaps ok)
        self._pps: dict[int, int] = {}  # pps id -> sps id
        self._prev_ref: int | None = None  # frame_num of the last reference picture
        self.losses = 0

    def reset(self) -> None:
        """Forget the order (after a loss the caller waits for a keyframe, whose IDR starts it again)."""
        self._prev_ref = None

    def check(self, data: bytes) -> bool:
        """True when a reference picture is missing between the previous packet and this one."""
        lost = False
        for start, end in nal_units(data):
            header = data[start]
            kind = header & 0x1F
            try:
                if kind == 7:
                    self._read_sps(_unescape(data[start + 1:min(end, start + 600)]))
                elif kind == 8:
                    r = BitReader(_unescape(data[start + 1:min(end, start + 16)]))
                    pps_id = r.ue()
                    self._pps[pps_id] = r.ue()
                elif kind in (1, 5):
                    lost = self._slice(_unescape(data[start + 1:min(end, start + 24)]), kind == 5,
                                       (header >> 5) & 3) or lost
            except (EOFError, ValueError):
                continue  # a header too short or damaged: say nothing about it
        if lost:
            self.losses += 1
        return lost

    def _read_sps(self, body: bytes) -> None:
        r = BitReader(body)
        profile = r.u(8)
        r.u(16)  # constraint flags, level
        sps_id = r.ue()
        separate = False
        if profile in _HIGH_PROFILES:
            chroma = r.ue()
            if chroma == 3:
                separate = bool(r.u(1))
            r.ue()  # bit depth luma
            r.ue()  # bit depth chroma
            r.u(1)  # qpprime_y_zero_transform_bypass
            if r.u(1):  # seq_scaling_matrix_present
                for i in range(8 if chroma != 3 else 12):
                    if r.u(1):
                        _skip_scaling_list(r, 16 if i < 6 else 64)
        log2_max_frame_num = r.ue() + 4
        poc_type = r.ue()
        if poc_type == 0:
            r.ue()
        elif poc_type == 1:
            r.u(1)
            r.se()
            r.se()
            for _ in range(r.ue()):
                r.se()
        r.ue()  # max_num_ref_frames
        gaps_allowed = bool(r.u(1))
        self._sps[sps_id] = (log2_max_frame_num, separate, gaps_allowed)

    def _slice(self, body: bytes, idr: bool, ref_idc: int) -> bool:
        r = BitReader(body)
        if r.ue() != 0:  # not the picture's first slice: its first slice was judged
            return False
        r.ue()  # slice_type
        sps_id = self._pps.get(r.ue())
        sps = self._sps.get(sps_id) if sps_id is not None else None
        if sps is None:
            return False
        log2_max, separate, gaps_allowed = sps
        if separate:
            r.u(2)
        frame_num = r.u(log2_max)
        if idr:
            self._prev_ref = frame_num
            return False
        lost = False
        prev = self._prev_ref
        if prev is not None and not gaps_allowed:
            lost = frame_num not in (prev, (prev + 1) % (1 << log2_max))
        if ref_idc:
            self._prev_ref = frame_num
        return lost


def _h264_key(data: bytes) -> bool:
    return any(data[s] & 0x1F == 5 for s, _e in nal_units(data))


def _h265_key(data: bytes) -> bool:
    return any(16 <= (data[s] >> 1) & 0x3F <= 23 for s, _e in nal_units(data))


def _vp9_key(data: bytes) -> bool:
    if not data:
        return False
    r = BitReader(data[:2])
    try:
        if r.u(2) != 2:  # frame_marker
            return False
        low, high = r.u(1), r.u(1)
        if (high << 1 | low) == 3:
            r.u(1)  # reserved
        if r.u(1):  # show_existing_frame
            return False
        return r.u(1) == 0  # frame_type: KEY_FRAME
    except EOFError:
        return False


def _leb128(data: bytes, i: int) -> tuple[int, int]:
    value = 0
    for k in range(8):
        if i >= len(data):
            raise EOFError("leb128 ends early")
        byte = data[i]
        i += 1
        value |= (byte & 0x7F) << (7 * k)
        if not byte & 0x80:
            return value, i
    raise ValueError("leb128 too long")


def _av1_key(data: bytes) -> bool:
    i, n = 0, len(data)
    try:
        while i < n:
            header = data[i]
            kind = (header >> 3) & 0x0F
            if kind == 1:  # OBU_SEQUENCE_HEADER
                return True
            i += 2 if header & 0x04 else 1  # the extension byte
            if not header & 0x02:  # no size field: this OBU runs to the end
                return False
            size, i = _leb128(data, i)
            i += size
    except (EOFError, ValueError):
        return False
    return False


_KEY = {"h264": _h264_key, "hevc": _h265_key, "vp9": _vp9_key, "av1": _av1_key}


def is_keyframe(codec: str, data: bytes) -> bool:
    """Whether ``data`` (one message's packet) starts a picture the decoder can draw on its own."""
    test = _KEY.get(codec)
    return bool(test and data and test(data))
