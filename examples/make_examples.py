#!/usr/bin/env python3
"""Writes the example inputs the README's commands use, into the folder given (default: the
folder of this script). Pure Python, no dependencies: every file is built here from formulas,
so a fresh clone has them after `make examples` (which `make` runs) and nothing binary is
checked in.

  triangles.tri       a few overlapping 2D triangles (the exact coverage test format)
  torus.ply           a binary little-endian PLY torus, 4,608 triangles, with normals
  torus.ply.gz        the same, gzip-compressed
  knot.obj            a (3,2) torus knot tube, 6,144 triangles, as OBJ
  spinning-box.gltf   a textured box on a ground, spinning (one 4 s rotation animation), lit by
                      a KHR_lights_punctual sun: texture, animation and shadows in one small file
  blob.raw            a 64x64x64 volume of uint16 (x fastest): two overlapping soft spheres
  thumbnails.jsonl    render jobs for `cuberille batch`: thumbnails of the models above, scene
                      paths relative to the repository root (where the README's commands run)
"""

import base64
import gzip
import json
import math
import os
import struct
import sys
import zlib


def write_tri(path):
    with open(path, "w") as f:
        f.write("# x0 y0 x1 y1 x2 y2 then a grey value or r g b (linear), in window pixels\n")
        f.write("10 10 100 20 30 90   1 0.2 0.2\n")
        f.write("50.5 5 120 60 60 120 0.3\n")
        f.write("5 120 64 64 20 70    0.2 0.8 0.3\n")
        f.write("70 100 126 90 100 126 0.1 0.3 1\n")


def wrapped_grid_faces(rows, columns, outward_when_j_turns_left):
    """Two triangles per cell of a grid of vertices (row i, column j at i * columns + j) that
    wraps in both directions, wound so their front faces point out of the surface."""
    faces = []
    for i in range(rows):
        for j in range(columns):
            a = i * columns + j
            b = ((i + 1) % rows) * columns + j
            c = ((i + 1) % rows) * columns + (j + 1) % columns
            d = i * columns + (j + 1) % columns
            faces += [(a, d, c), (a, c, b)] if outward_when_j_turns_left else [(a, b, c), (a, c, d)]
    return faces


def torus(major=1.0, minor=0.35, rings=48, sides=48):
    vertices, normals, faces = [], [], []
    for i in range(rings):
        u = 2 * math.pi * i / rings
        for j in range(sides):
            v = 2 * math.pi * j / sides
            n = (math.cos(u) * math.cos(v), math.sin(v), math.sin(u) * math.cos(v))
            vertices.append((math.cos(u) * (major + minor * math.cos(v)), minor * math.sin(v),
                             math.sin(u) * (major + minor * math.cos(v))))
            normals.append(n)
    return vertices, normals, wrapped_grid_faces(rings, sides, outward_when_j_turns_left=True)


def ply_bytes(vertices, normals, faces):
    header = ("ply\nformat binary_little_endian 1.0\ncomment made by examples/make_examples.py\n"
              f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    body = bytearray()
    for p, n in zip(vertices, normals):
        body += struct.pack("<6f", *p, *n)
    for f in faces:
        body += struct.pack("<B3i", 3, *f)
    return header.encode() + bytes(body)


def knot(p=3, q=2, segments=192, sides=16, radius=0.18):
    def centre(t):
        r = 1.0 + 0.45 * math.cos(q * t)
        return (r * math.cos(p * t), 0.45 * math.sin(q * t), r * math.sin(p * t))
    vertices, faces = [], []
    for i in range(segments):
        t = 2 * math.pi * i / segments
        c, c2 = centre(t), centre(t + 1e-3)
        tangent = [b - a for a, b in zip(c, c2)]
        length = math.sqrt(sum(x * x for x in tangent))
        tangent = [x / length for x in tangent]
        up = (0.0, 1.0, 0.0)
        side = (tangent[1] * up[2] - tangent[2] * up[1], tangent[2] * up[0] - tangent[0] * up[2],
                tangent[0] * up[1] - tangent[1] * up[0])
        sl = math.sqrt(sum(x * x for x in side))
        side = [x / sl for x in side]
        normal = (side[1] * tangent[2] - side[2] * tangent[1], side[2] * tangent[0] - side[0] * tangent[2],
                  side[0] * tangent[1] - side[1] * tangent[0])
        for j in range(sides):
            a = 2 * math.pi * j / sides
            vertices.append(tuple(c[k] + radius * (math.cos(a) * side[k] + math.sin(a) * normal[k]) for k in range(3)))
    return vertices, wrapped_grid_faces(segments, sides, outward_when_j_turns_left=False)


def write_obj(path, vertices, faces):
    with open(path, "w") as f:
        f.write("# a (3,2) torus knot tube, made by examples/make_examples.py\n")
        for v in vertices:
            f.write("v %.6f %.6f %.6f\n" % v)
        for a, b, c in faces:
            f.write(f"f {a + 1} {b + 1} {c + 1}\n")


def png_bytes(width, height, rgb_rows):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + bytes(row) for row in rgb_rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def data_uri(mime, data):
    return f"data:{mime};base64," + base64.b64encode(data).decode()


def sun_rotation(pitch_degrees, yaw_degrees):
    """The node rotation (x, y, z, w) that turns a light's -Z axis down by the pitch, then about
    +Y by the yaw: here the sun shines down towards +x and +z, so the box's shadow falls on the
    ground in view."""
    a, b = math.radians(pitch_degrees) / 2, math.radians(yaw_degrees) / 2
    qx = (math.sin(a), 0.0, 0.0, math.cos(a))
    qy = (0.0, math.sin(b), 0.0, math.cos(b))
    x1, y1, z1, w1 = qy
    x2, y2, z2, w2 = qx
    return [w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2, w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2]


def write_gltf(path):
    # A unit box (24 vertices: a face each, with UVs) and a ground quad, in one buffer.
    positions, normals, uvs, indices = [], [], [], []
    faces = [((1, 0, 0), (0, 0, -1), (0, 1, 0)), ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
             ((0, 1, 0), (1, 0, 0), (0, 0, -1)), ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
             ((0, 0, 1), (1, 0, 0), (0, 1, 0)), ((0, 0, -1), (-1, 0, 0), (0, 1, 0))]
    for n, s, t in faces:
        base = len(positions)
        for (a, b) in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            positions.append(tuple(0.5 * (n[k] + a * s[k] + b * t[k]) for k in range(3)))
            normals.append(n)
            uvs.append(((a + 1) / 2, (1 - b) / 2))
        indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    box_vertices, box_indices = len(positions), len(indices)
    ground = len(positions)
    for (x, z) in ((-3, 3), (3, 3), (3, -3), (-3, -3)):
        positions.append((x, -0.5, z))
        normals.append((0, 1, 0))
        uvs.append((0, 0))
    indices += [ground, ground + 1, ground + 2, ground, ground + 2, ground + 3]
    times = [0.0, 1.0, 2.0, 3.0, 4.0]
    rotations = []
    for k in range(5):
        angle = math.pi * k / 2
        rotations.append((0.0, math.sin(angle / 2), 0.0, math.cos(angle / 2)))

    blob = bytearray()
    def add(data):
        offset = len(blob)
        blob.extend(data)
        while len(blob) % 4:
            blob.append(0)
        return offset, len(data)
    views = []
    for data in (b"".join(struct.pack("<3f", *p) for p in positions),
                 b"".join(struct.pack("<3f", *n) for n in normals),
                 b"".join(struct.pack("<2f", *u) for u in uvs),
                 b"".join(struct.pack("<H", i) for i in indices),
                 b"".join(struct.pack("<f", t) for t in times),
                 b"".join(struct.pack("<4f", *r) for r in rotations)):
        offset, length = add(data)
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": length})
    lo = [min(p[k] for p in positions) for k in range(3)]
    hi = [max(p[k] for p in positions) for k in range(3)]
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": len(positions), "type": "VEC3", "min": lo, "max": hi},
        {"bufferView": 1, "componentType": 5126, "count": len(normals), "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": len(uvs), "type": "VEC2"},
        {"bufferView": 3, "componentType": 5123, "count": box_indices, "type": "SCALAR"},
        {"bufferView": 3, "byteOffset": box_indices * 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        {"bufferView": 4, "componentType": 5126, "count": 5, "type": "SCALAR", "min": [0.0], "max": [4.0]},
        {"bufferView": 5, "componentType": 5126, "count": 5, "type": "VEC4"},
    ]
    checker = [[c for x in range(16) for c in ((235, 120, 40) if (x // 4 + y // 4) % 2 else (250, 235, 200))]
               for y in range(16)]
    doc = {
        "asset": {"version": "2.0", "generator": "cuberille examples/make_examples.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 3.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0, "name": "box"}, {"mesh": 1, "name": "ground"},
                  {"name": "sun", "rotation": sun_rotation(pitch_degrees=-55, yaw_degrees=-120),
                   "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3, "material": 0}]},
                   {"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 4, "material": 1}]}],
        "materials": [{"name": "checker", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 0.6}},
                      {"name": "ground", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.62, 0.65, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9987}],
        "images": [{"uri": data_uri("image/png", png_bytes(16, 16, checker))}],
        "animations": [{"name": "spin", "channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}],
                        "samplers": [{"input": 5, "output": 6, "interpolation": "LINEAR"}]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": data_uri("application/octet-stream", bytes(blob))}],
    }
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def write_volume(path, n=64):
    values = bytearray()
    for z in range(n):
        for y in range(n):
            for x in range(n):
                d1 = math.dist((x, y, z), (26, 30, 32)) / 16.0
                d2 = math.dist((x, y, z), (40, 34, 30)) / 12.0
                v = max(0.0, 1.0 - min(d1, d2))
                values += struct.pack("<H", int(round(1000 * v)))
    with open(path, "wb") as f:
        f.write(values)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    os.makedirs(out, exist_ok=True)
    write_tri(os.path.join(out, "triangles.tri"))
    ply = ply_bytes(*torus())
    with open(os.path.join(out, "torus.ply"), "wb") as f:
        f.write(ply)
    with open(os.path.join(out, "torus.ply.gz"), "wb") as f:
        f.write(gzip.compress(ply, mtime=0))
    write_obj(os.path.join(out, "knot.obj"), *knot())
    write_gltf(os.path.join(out, "spinning-box.gltf"))
    write_volume(os.path.join(out, "blob.raw"))
    write_jobs(os.path.join(out, "thumbnails.jsonl"))


def write_jobs(path):
    """Four views of each mesh and two moments of the animation, as `cuberille batch` takes them:
    one JSON object per line, render's options by name."""
    jobs = []
    for model in ("torus.ply", "knot.obj"):
        for azimuth in (0, 90, 180, 270):
            jobs.append({"scene": f"examples/{model}", "out": f"thumb-{model.split('.')[0]}-{azimuth}.png",
                         "width": 256, "height": 256, "msaa": 4, "azimuth": azimuth})
    for seconds in (0.5, 1.5):
        jobs.append({"scene": "examples/spinning-box.gltf", "out": f"thumb-box-{seconds}s.png", "width": 256,
                     "height": 256, "msaa": 4, "time": seconds, "shadows": "hybrid", "zoom": 2})
    with open(path, "w") as f:
        f.write("# cuberille batch examples/thumbnails.jsonl: one render job per line\n")
        for job in jobs:
            f.write(json.dumps(job) + "\n")


if __name__ == "__main__":
    main()
