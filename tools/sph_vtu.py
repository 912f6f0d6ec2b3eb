"""Reads the VTU frames sph-run writes (VTK XML UnstructuredGrid) with numpy only.

Follows the VTK XML file-format specification: the XML header is parsed as XML; arrays are
either `format="ascii"` or `format="appended"` with `<AppendedData encoding="raw">`, where the
data starts after the '_' and every array's bytes are preceded by their byte count, one
integer of the file's `header_type` (UInt32 when absent), in the file's `byte_order`.
Compressed or base64 data (other writers) is reported as unsupported, not guessed at.

    frame = read_vtu("out/dam_break/frames/frame_00012.vtu")
    frame.time, frame.points (n x 3), frame.point_data["dt"] (n,), frame.path
"""
import pathlib
import xml.etree.ElementTree as ET

from sph_python import need  # noqa: E402 (tools/ is the script's folder)

need("numpy")
import numpy as np  # noqa: E402

_TYPES = {"Int8": "i1", "UInt8": "u1", "Int16": "i2", "UInt16": "u2", "Int32": "i4", "UInt32": "u4",
          "Int64": "i8", "UInt64": "u8", "Float32": "f4", "Float64": "f8"}


class VtuError(Exception):
    """A file that is not a VTU frame this reader understands; the message names the file."""


class Frame:
    def __init__(self, path, time, points, point_data, types):
        self.path = path
        self.time = time              # FieldData TimeValue (s), or None
        self.points = points          # (n, 3)
        self.point_data = point_data  # name -> (n,) or (n, k) array
        self.types = types            # name -> VTK type name as declared ("Float64", "UInt8", ...)

    @property
    def n(self):
        return len(self.points)


def read_vtu(path):
    path = pathlib.Path(path)
    if not path.is_file():
        raise VtuError(f"{path}: no such file")
    data = path.read_bytes()
    mark = data.find(b"<AppendedData")
    if mark >= 0:
        start = data.find(b">", mark)
        under = data.find(b"_", start)
        if start < 0 or under < 0:
            raise VtuError(f"{path}: <AppendedData> without the '_' that starts the raw data")
        head = data[:start + 1] + b"</AppendedData></VTKFile>"
        base = under + 1
    else:
        head, base = data, None
    try:
        root = ET.fromstring(head)
    except ET.ParseError as e:
        raise VtuError(f"{path}: not a VTK XML file ({e})") from None
    if root.tag != "VTKFile" or root.get("type") != "UnstructuredGrid":
        raise VtuError(f"{path}: expected <VTKFile type=\"UnstructuredGrid\">, found <{root.tag} "
                       f"type=\"{root.get('type')}\">")
    if root.get("compressor"):
        raise VtuError(f"{path}: compressed data ({root.get('compressor')}) is not supported")
    endian = "<" if root.get("byte_order", "LittleEndian") == "LittleEndian" else ">"
    header_type = root.get("header_type", "UInt32")
    if header_type not in ("UInt32", "UInt64"):
        raise VtuError(f"{path}: header_type \"{header_type}\", expected UInt32 or UInt64")
    header_dtype = np.dtype(endian + _TYPES[header_type])
    appended = root.find("AppendedData")
    if appended is not None and appended.get("encoding", "raw") != "raw":
        raise VtuError(f"{path}: AppendedData encoding \"{appended.get('encoding')}\", expected raw")
    piece = root.find("UnstructuredGrid/Piece")
    if piece is None:
        raise VtuError(f"{path}: no <UnstructuredGrid><Piece>")
    try:
        n = int(piece.get("NumberOfPoints", "0"))
    except ValueError:
        raise VtuError(f"{path}: NumberOfPoints \"{piece.get('NumberOfPoints')}\" is not an integer") from None

    def array(el, count):
        vtype = el.get("type")
        if vtype not in _TYPES:
            raise VtuError(f"{path}: DataArray \"{el.get('Name')}\" has type \"{vtype}\", expected one of "
                           + ", ".join(_TYPES))
        dtype = np.dtype(endian + _TYPES[vtype])
        fmt = el.get("format")
        try:
            comps = int(el.get("NumberOfComponents", "1"))
            offset = int(el.get("offset")) if fmt == "appended" else 0
        except (TypeError, ValueError):
            raise VtuError(f"{path}: DataArray \"{el.get('Name')}\" has no valid NumberOfComponents or offset") from None
        if comps < 1 or offset < 0:
            raise VtuError(f"{path}: DataArray \"{el.get('Name')}\": NumberOfComponents {comps}, offset {offset}")
        if fmt == "ascii":
            try:
                a = np.array((el.text or "").split(), dtype=dtype)
            except ValueError:
                raise VtuError(f"{path}: DataArray \"{el.get('Name')}\": ascii values that are not {vtype}") from None
            if count is not None and a.size != count * comps:
                raise VtuError(f"{path}: DataArray \"{el.get('Name')}\": {a.size} ascii values, expected {count * comps} "
                               f"({count} tuples x {comps})")
        elif fmt == "appended":
            if base is None:
                raise VtuError(f"{path}: DataArray \"{el.get('Name')}\" is appended but the file has no AppendedData")
            off = base + offset
            if off + header_dtype.itemsize > len(data):
                raise VtuError(f"{path}: DataArray \"{el.get('Name')}\" starts past the end of the file (truncated?)")
            nbytes = int(np.frombuffer(data, header_dtype, 1, off)[0])
            expected = None if count is None else count * comps * dtype.itemsize
            if expected is not None and nbytes != expected:
                raise VtuError(f"{path}: DataArray \"{el.get('Name')}\": block header says {nbytes} bytes, expected "
                               f"{expected} ({count} tuples x {comps} x {dtype.itemsize} bytes)")
            if off + header_dtype.itemsize + nbytes > len(data):
                raise VtuError(f"{path}: DataArray \"{el.get('Name')}\" runs past the end of the file (truncated?)")
            a = np.frombuffer(data, dtype, nbytes // dtype.itemsize, off + header_dtype.itemsize)
        else:
            raise VtuError(f"{path}: DataArray \"{el.get('Name')}\" has format \"{fmt}\", expected ascii or appended")
        a = a.astype(dtype.newbyteorder("="), copy=False)
        return a.reshape(-1, comps) if comps != 1 else a

    time = None
    for el in root.iterfind("UnstructuredGrid/FieldData/DataArray"):
        if el.get("Name") == "TimeValue":
            values = array(el, None)
            if values.size == 0:
                raise VtuError(f"{path}: TimeValue holds no value")
            time = float(values.flat[0])
    pts = piece.find("Points/DataArray")
    if pts is None:
        raise VtuError(f"{path}: no <Points> array")
    points = array(pts, n)
    point_data, types = {}, {}
    for el in piece.iterfind("PointData/DataArray"):
        point_data[el.get("Name")] = array(el, n)
        types[el.get("Name")] = el.get("type")
    return Frame(path, time, points, point_data, types)


def frame_files(inputs):
    """Expands inputs (files, frame directories, or run directories holding frames/) into a
    sorted list of .vtu paths. Raises VtuError for a missing path or a directory without frames."""
    files = []
    for item in inputs:
        p = pathlib.Path(item)
        if p.is_dir():
            found = sorted(p.glob("frame_*.vtu")) or sorted((p / "frames").glob("frame_*.vtu"))
            if not found:
                raise VtuError(f"{p}: no .vtu frames in it (nor in {p / 'frames'})")
            files += found
        elif p.is_file():
            files.append(p)
        else:
            raise VtuError(f"{p}: no such file or directory")
    return files
