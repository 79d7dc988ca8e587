"""Minimal readers for the VTK files surge writes (Python 3 standard library + numpy only).

read_vtp(path) -> dict
    Reads a VTK XML PolyData file whose arrays are in a raw <AppendedData> block (as written by
    surge_vtp_write), honouring byte_order and header_type (UInt32 or UInt64). Returns:
      "points"              float array (n, 3)
      "verts_connectivity"  / "verts_offsets" (when the file has Verts)
      one entry per PointData array, by name: shape (n,) or (n, k)
      one entry per FieldData array, by name: a Python scalar when it holds a single value
      (e.g. "time_s" -> float, "step" -> int), else an array.

read_pvd(path) -> list of (time: float, file: str)
    The <DataSet> entries of a .pvd time collection, in file order.

write_vtp(path, points, point_data, time_s, step)
    Writes a snapshot in the format of surge_vtp_write (sim/src/vtk_output.c), byte for byte for
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
    if appended.get("encoding") != "raw":
        raise ValueError("unsupported AppendedData encoding %r" % appended.get("encoding"))
    return root, marker + 1


def _decode(data, base, array, endian, header_dtype):
    """Decodes one appended DataArray element into a numpy array of shape (n,) or (n, k)."""
    if array.get("format") != "appended":
        raise ValueError("array %r: only format=\"appended\" is supported" % array.get("Name"))
    type_name = array.get("type")
    if type_name not in _TYPES:
        raise ValueError("array %r: unsupported type %r" % (array.get("Name"), type_name))
    dtype = np.dtype(endian + _TYPES[type_name])
    start = base + int(array.get("offset"))
    header = np.frombuffer(data, dtype=header_dtype, count=1, offset=start)
    nbytes = int(header[0])
    start += header_dtype.itemsize
    if nbytes % dtype.itemsize != 0 or start + nbytes > len(data):
        raise ValueError("array %r: bad block size %d" % (array.get("Name"), nbytes))
    values = np.frombuffer(data, dtype=dtype, count=nbytes // dtype.itemsize, offset=start)
    values = values.astype(dtype.newbyteorder("="))  # native byte order, owned copy
    ncomp = int(array.get("NumberOfComponents", "1"))
    if ncomp > 1:
        if values.size % ncomp != 0:
            raise ValueError("array %r: size %d not a multiple of %d" % (array.get("Name"), values.size, ncomp))
        values = values.reshape(-1, ncomp)
    return values


def read_vtp(path):
    with open(path, "rb") as f:
        data = f.read()
    root, base = _split(data)
    if root.get("type") != "PolyData":
        raise ValueError("%s: not a PolyData file (type=%r)" % (path, root.get("type")))
    if root.get("compressor"):
        raise ValueError("%s: compressed files are not supported" % path)
    endian = {"LittleEndian": "<", "BigEndian": ">"}[root.get("byte_order", "LittleEndian")]
    header_type = root.get("header_type", "UInt32")
    if header_type not in ("UInt32", "UInt64"):
        raise ValueError("%s: unsupported header_type %r" % (path, header_type))
    header_dtype = np.dtype(endian + _TYPES[header_type])

    poly = root.find("PolyData")
    pieces = poly.findall("Piece")
    if len(pieces) != 1:
        raise ValueError("%s: expected one Piece, found %d" % (path, len(pieces)))
    piece = pieces[0]
    n = int(piece.get("NumberOfPoints"))

    def decode(array):
        return _decode(data, base, array, endian, header_dtype)

    result = {}
    points = decode(piece.find("Points/DataArray")).reshape(-1, 3)
    if points.shape[0] != n:
        raise ValueError("%s: %d points, header says %d" % (path, points.shape[0], n))
    result["points"] = points
    for array in piece.findall("Verts/DataArray"):
        result["verts_" + array.get("Name")] = decode(array)
    for array in piece.findall("PointData/DataArray"):
        values = decode(array)
        if values.shape[0] != n:
            raise ValueError("%s: array %r has %d tuples, expected %d" % (path, array.get("Name"), values.shape[0], n))
        result[array.get("Name")] = values
    for array in poly.findall("FieldData/DataArray"):
        name = array.get("Name")
        if name in result:
            raise ValueError("%s: field data %r clashes with another array" % (path, name))
        values = decode(array)
        result[name] = values.reshape(-1)[0].item() if values.size == 1 else values
    return result


def read_pvd(path):
    root = ET.parse(path).getroot()
    if root.get("type") != "Collection":
        raise ValueError("%s: not a Collection file (type=%r)" % (path, root.get("type")))
    return [(float(d.get("timestep")), d.get("file")) for d in root.findall("Collection/DataSet")]


# ------------------------------------------------------------------------------------------------
# Writers (same bytes as sim/src/vtk_output.c)
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
