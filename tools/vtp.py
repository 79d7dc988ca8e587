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
"""

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
