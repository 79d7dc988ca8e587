"""Minimal readers for the VTK files surge writes (Python 3 standard library + numpy only).

read_vtp(path, required=(), finite=False) -> dict
    Reads a VTK XML PolyData file whose arrays are in a raw <AppendedData> block (as written by
    surge_vtp_write), honouring byte_order and header_type (UInt32 or UInt64). Returns:
      "points"              float array (n, 3)
      "verts_connectivity"  / "verts_offsets" (when the file has Verts)
      one entry per PointData array, by name: shape (n,) or (n, k)
      one entry per FieldData array, by name: a Python scalar when it holds a single value
      (e.g. "time_s" -> float, "step" -> int), else an array.
    required names arrays the caller needs (with finite=True: holding finite values only).

read_pvd(path) -> list of (time: float, file: str)
    The <DataSet> entries of a .pvd time collection, in file order.

Both raise VtpError (a ValueError), its message naming the file and what is wrong, for a file that cannot be read
or is malformed, or lacks a required array.

write_vtp(path, points, point_data, time_s, step)
    Writes a snapshot in the format of surge_vtp_write (sim/src/io/vtk_output.c), byte for byte for
    the same values: VTK XML PolyData, little endian, header_type UInt64, raw appended data, field
    data time_s (Float64) and step (Int64), point data velocity_mps (Float32 x3), density_kgpm3,
    pressure_pa (Float32), kind (UInt8), id (Int32), Float64 points and Int64 verts (one vertex
    per point). points may be (n, 2) or (n, 3) (z is written as 0 like the C writer), and so may
    velocity_mps. A standard array missing from point_data is written as zeros (id: 0..n-1).
    Other arrays in point_data are appended after id, typed from their numpy dtype.
    Like the C writer it writes "<path>.tmp" and renames it over path.

write_pvd(path, entries)
    Writes a .pvd time collection of (time_s, file) entries as surge_pvd_open/surge_pvd_add do.

Synthetic runs for tests are built with these two (see tests/test_freydier_metrics.py).
"""

import math
import os
import xml.etree.ElementTree as ET

import numpy as np

_TYPES = {
    "Int8": "i1", "UInt8": "u1",
    "Int16": "i2", "UInt16": "u2",
    "Int32": "i4", "UInt32": "u4",
    "Int64": "i8", "UInt64": "u8",
    "Float32": "f4", "Float64": "f8",
}


class VtpError(ValueError):
    """A .vtp or .pvd file that cannot be read, or lacks what the caller needs; the message names the file."""


def _int(element, name, default=None):
    """An integer attribute of an XML element (default where it is absent; ValueError if that is None)."""
    text = element.get(name, default)
    if text is None:
        raise ValueError("<%s> has no %s attribute" % (element.tag, name))
    try:
        return int(text)
    except ValueError:
        raise ValueError("<%s> %s=%r is not an integer" % (element.tag, name, text))


def _split(data):
    """Returns (xml_root, offset of the first byte after the '_' marker) for a raw-appended file."""
    tag = data.find(b"<AppendedData")
    if tag < 0:
        raise ValueError("no <AppendedData> block")
    tag_close = data.find(b">", tag)
    marker = data.find(b"_", tag_close)
    if tag_close < 0 or marker < 0 or data[tag_close + 1:marker].strip():
        raise ValueError("malformed <AppendedData> block")
    # Parse the header only: everything up to the opening AppendedData tag, closed by hand.
    root = ET.fromstring(data[:tag_close + 1] + b"</AppendedData></VTKFile>")
    appended = root.find("AppendedData")
    if appended is None:
        raise ValueError("<AppendedData> is not an element of <VTKFile>")
    if appended.get("encoding") != "raw":
        raise ValueError("unsupported AppendedData encoding %r" % appended.get("encoding"))
    return root, marker + 1


def _decode(data, base, array, endian, header_dtype):
    """Decodes one appended DataArray element into a numpy array of shape (n,) or (n, k)."""
    name = array.get("Name")
    if array.get("format") != "appended":
        raise ValueError("array %r: only format=\"appended\" is supported" % name)
    type_name = array.get("type")
    if type_name not in _TYPES:
        raise ValueError("array %r: unsupported type %r" % (name, type_name))
    dtype = np.dtype(endian + _TYPES[type_name])
    start = base + _int(array, "offset")
    if not base <= start <= len(data) - header_dtype.itemsize:
        raise ValueError("array %r: offset %d is outside the appended data" % (name, start - base))
    nbytes = int(np.frombuffer(data, dtype=header_dtype, count=1, offset=start)[0])
    start += header_dtype.itemsize
    if nbytes % dtype.itemsize != 0 or start + nbytes > len(data):
        raise ValueError("array %r: bad block size %d" % (name, nbytes))
    values = np.frombuffer(data, dtype=dtype, count=nbytes // dtype.itemsize, offset=start)
    values = values.astype(dtype.newbyteorder("="))  # native byte order, owned copy
    ncomp = _int(array, "NumberOfComponents", "1")
    if ncomp < 1 or values.size % ncomp != 0:
        raise ValueError("array %r: size %d not a multiple of %d components" % (name, values.size, ncomp))
    return values.reshape(-1, ncomp) if ncomp > 1 else values


def _parse_vtp(data):
    """The arrays of a VTK XML PolyData file's bytes (see read_vtp); ValueError or ET.ParseError if malformed."""
    root, base = _split(data)
    if root.get("type") != "PolyData":
        raise ValueError("not a PolyData file (type=%r)" % root.get("type"))
    if root.get("compressor"):
        raise ValueError("compressed files are not supported")
    byte_order = root.get("byte_order", "LittleEndian")
    if byte_order not in ("LittleEndian", "BigEndian"):
        raise ValueError("unknown byte_order %r" % byte_order)
    endian = "<" if byte_order == "LittleEndian" else ">"
    header_type = root.get("header_type", "UInt32")
    if header_type not in ("UInt32", "UInt64"):
        raise ValueError("unsupported header_type %r" % header_type)
    header_dtype = np.dtype(endian + _TYPES[header_type])

    poly = root.find("PolyData")
    pieces = poly.findall("Piece") if poly is not None else []
    if len(pieces) != 1:
        raise ValueError("expected one <PolyData><Piece>, found %d" % len(pieces))
    piece = pieces[0]
    n = _int(piece, "NumberOfPoints")

    def decode(array):
        if array.get("Name") is None:
            raise ValueError("a <DataArray> has no Name")
        return _decode(data, base, array, endian, header_dtype)

    result = {}
    points = piece.find("Points/DataArray")
    if points is None:
        raise ValueError("no <Points> array")
    points = decode(points)
    if points.size != 3 * n:
        raise ValueError("%d point coordinates, expected 3 x %d" % (points.size, n))
    result["points"] = points.reshape(n, 3)
    for array in piece.findall("Verts/DataArray"):
        result["verts_" + array.get("Name")] = decode(array)
    for array in piece.findall("PointData/DataArray"):
        values = decode(array)
        if values.shape[0] != n:
            raise ValueError("array %r has %d tuples, expected %d" % (array.get("Name"), values.shape[0], n))
        result[array.get("Name")] = values
    for array in poly.findall("FieldData/DataArray"):
        name = array.get("Name")
        if name in result:
            raise ValueError("field data %r clashes with another array" % name)
        values = decode(array)
        result[name] = values.reshape(-1)[0].item() if values.size == 1 else values
    return result


def read_vtp(path, required=(), finite=False):
    """The arrays of a snapshot (see the module's docstring). required: names of arrays the caller needs, and with
    finite=True these must hold finite values only. Raises VtpError, naming the file and what is wrong, for a file
    that cannot be read or is malformed, or lacks a required array."""
    try:
        with open(path, "rb") as f:
            data = f.read()
        result = _parse_vtp(data)
    except OSError as e:
        raise VtpError("%s: cannot read it (%s)" % (path, e.strerror or e))
    except ET.ParseError as e:
        raise VtpError("%s: malformed XML (%s)" % (path, e))
    except ValueError as e:
        raise VtpError("%s: %s" % (path, e))
    for name in required:
        if name not in result:
            raise VtpError("%s: no %s array" % (path, name))
        if finite and not np.all(np.isfinite(result[name])):
            raise VtpError("%s: non-finite values (NaN or infinity) in %s" % (path, name))
    return result


def read_pvd(path):
    """The (time, file) entries of a .pvd collection; VtpError naming the file if it is unreadable or malformed."""
    try:
        root = ET.parse(path).getroot()
    except OSError as e:
        raise VtpError("%s: cannot read it (%s)" % (path, e.strerror or e))
    except ET.ParseError as e:
        raise VtpError("%s: malformed XML (%s)" % (path, e))
    if root.get("type") != "Collection":
        raise VtpError("%s: not a Collection file (type=%r)" % (path, root.get("type")))
    entries = []
    for k, dataset in enumerate(root.findall("Collection/DataSet")):
        timestep, file = dataset.get("timestep"), dataset.get("file")
        try:
            time_s = float(timestep)
        except (TypeError, ValueError):
            time_s = math.nan
        if not math.isfinite(time_s) or not file:
            raise VtpError("%s: <DataSet> %d has timestep=%r file=%r, expected a time and a file name"
                           % (path, k + 1, timestep, file))
        entries.append((time_s, file))
    return entries


# ------------------------------------------------------------------------------------------------
# Writers (same bytes as sim/src/io/vtk_output.c)
# ------------------------------------------------------------------------------------------------

# The C writer's point data arrays, in its order: (name, VTK type, number of components).
_STANDARD_ARRAYS = (
    ("velocity_mps", "Float32", 3),
    ("density_kgpm3", "Float32", 1),
    ("pressure_pa", "Float32", 1),
    ("kind", "UInt8", 1),
    ("id", "Int32", 1),
)

_VTK_NAMES = {np.dtype(v).str[1:]: k for k, v in _TYPES.items()}  # "f8" -> "Float64", ...


def _xyz(values, n, name):
    """(n, 2) or (n, 3) -> (n, 3) float64 with z = 0 where absent."""
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 2 or values.shape[0] != n or values.shape[1] not in (2, 3):
        raise ValueError("%s: expected shape (%d, 2) or (%d, 3), got %s" % (name, n, n, values.shape))
    out = np.zeros((n, 3))
    out[:, :2] = values[:, :2]  # the C writer always writes z = 0
    return out


def _xml_escape(text):
    return (text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
            .replace('"', "&quot;").replace("'", "&apos;"))


def write_vtp(path, points, point_data, time_s, step):
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2:
        raise ValueError("points: expected a 2-D array, got shape %s" % (points.shape,))
    n = points.shape[0]
    points = _xyz(points, n, "points")
    point_data = dict(point_data)

    arrays = []  # (name, vtk type, ncomp, little-endian numpy array)
    for name, vtk_type, ncomp in _STANDARD_ARRAYS:
        dtype = np.dtype("<" + _TYPES[vtk_type])
        values = point_data.pop(name, None)
        if values is None:
            values = np.arange(n) if name == "id" else np.zeros((n, ncomp) if ncomp > 1 else n)
        if ncomp == 3:
            values = _xyz(values, n, name)
        else:
            values = np.asarray(values).reshape(-1)
            if values.shape[0] != n:
                raise ValueError("%s: %d values for %d points" % (name, values.shape[0], n))
        arrays.append((name, vtk_type, ncomp, values.astype(dtype)))
    for name, values in point_data.items():
        values = np.asarray(values)
        if values.shape[:1] != (n,) or values.ndim > 2:
            raise ValueError("%s: expected shape (%d,) or (%d, k), got %s" % (name, n, n, values.shape))
        key = values.dtype.str[1:]
        if key not in _VTK_NAMES:
            raise ValueError("%s: unsupported dtype %s" % (name, values.dtype))
        ncomp = values.shape[1] if values.ndim == 2 else 1
        arrays.append((name, _VTK_NAMES[key], ncomp, values.astype(values.dtype.newbyteorder("<"))))

    header = []
    blocks = []
    offset = 0

    def tag(indent, vtk_type, name, ncomp, data):
        nonlocal offset
        extra = 'NumberOfTuples="1" ' if ncomp == 0 else (
            'NumberOfComponents="%d" ' % ncomp if ncomp > 1 else "")
        header.append('%s<DataArray type="%s" Name="%s" %sformat="appended" offset="%d"/>\n'
                      % (indent, vtk_type, _xml_escape(name), extra, offset))
        raw = np.ascontiguousarray(data).tobytes()
        blocks.append(np.array([len(raw)], dtype="<u8").tobytes() + raw)
        offset += 8 + len(raw)

    in3, in4 = " " * 6, " " * 8
    header.append('<?xml version="1.0"?>\n'
                  '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n'
                  "  <PolyData>\n"
                  "    <FieldData>\n")
    tag(in3, "Float64", "time_s", 0, np.array([time_s], dtype="<f8"))
    tag(in3, "Int64", "step", 0, np.array([step], dtype="<i8"))
    header.append("    </FieldData>\n"
                  '    <Piece NumberOfPoints="%d" NumberOfVerts="%d" NumberOfLines="0" '
                  'NumberOfStrips="0" NumberOfPolys="0">\n'
                  '      <PointData Scalars="density_kgpm3" Vectors="velocity_mps">\n' % (n, n))
    for name, vtk_type, ncomp, values in arrays:
        tag(in4, vtk_type, name, ncomp, values)
    header.append("      </PointData>\n"
                  "      <Points>\n")
    tag(in4, "Float64", "Points", 3, points.astype("<f8"))
    header.append("      </Points>\n"
                  "      <Verts>\n")
    tag(in4, "Int64", "connectivity", 1, np.arange(n, dtype="<i8"))
    tag(in4, "Int64", "offsets", 1, np.arange(1, n + 1, dtype="<i8"))
    header.append("      </Verts>\n"
                  "    </Piece>\n"
                  "  </PolyData>\n"
                  '  <AppendedData encoding="raw">\n'
                  "   _")
    data = "".join(header).encode() + b"".join(blocks) + b"\n  </AppendedData>\n</VTKFile>\n"
    _write_atomic(path, data)


def write_pvd(path, entries):
    lines = ['<?xml version="1.0"?>\n'
             '<VTKFile type="Collection" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n'
             "  <Collection>\n"]
    for time_s, file in entries:
        lines.append('    <DataSet timestep="%.17g" group="" part="0" file="%s"/>\n'
                     % (float(time_s), _xml_escape(str(file))))
    lines.append("  </Collection>\n"
                 "</VTKFile>\n")
    _write_atomic(path, "".join(lines).encode())


def _write_atomic(path, data):
    tmp = str(path) + ".tmp"
    try:
        with open(tmp, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
