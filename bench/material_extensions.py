#!/usr/bin/env python3
"""What each glTF material extension and the environment cost per frame: a model rendered as it
ships and with one extension given to every material, in turns (pairs, so the VM's drift falls on
both), through the Python module; the ratio is the median of the pairs' ratios.
Usage (from the repository root, after `make`):
  python3 bench/material_extensions.py [--build build/release] [--pairs 7] [--size 1920x1080] [MODEL.gltf|.glb ...]
Default models: ../shared/data's MetalRoughSpheresNoTextures and DamagedHelmet. Prints a Markdown
table for docs/performance.md, with the effect counter that proves the extension ran on every
shaded pixel it claims."""

import argparse
import copy
import json
import shutil
import statistics
import struct
import sys
import tempfile
from pathlib import Path

REPOSITORY = Path(__file__).resolve().parents[1]
DATA = REPOSITORY.parent / "shared" / "data" / "gltf"
DEFAULT_MODELS = [DATA / "MetalRoughSpheresNoTextures" / "glTF" / "MetalRoughSpheresNoTextures.gltf",
                  DATA / "DamagedHelmet" / "DamagedHelmet.glb"]

# (row name, the extension's name or None, its JSON for every material, the counter that proves it
# ran, extra render options). Values typical of exporters' output.
VARIANTS = [
    ("KHR_materials_emissive_strength", "KHR_materials_emissive_strength", {"emissiveStrength": 4.0}, None, {}),
    ("KHR_materials_ior", "KHR_materials_ior", {"ior": 1.7}, None, {}),
    ("KHR_materials_specular", "KHR_materials_specular",
     {"specularFactor": 0.8, "specularColorFactor": [1.0, 0.9, 0.8]}, "dielectricSpecularPixels", {}),
    ("KHR_materials_pbrSpecularGlossiness", "KHR_materials_pbrSpecularGlossiness",
     {"diffuseFactor": [0.8, 0.6, 0.4, 1.0], "specularFactor": [0.2, 0.2, 0.2], "glossinessFactor": 0.6},
     "specularGlossinessPixels", {}),
    ("KHR_materials_clearcoat", "KHR_materials_clearcoat", {"clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.1},
     "clearcoatPixels", {}),
    ("KHR_materials_sheen", "KHR_materials_sheen", {"sheenColorFactor": [0.8, 0.8, 0.8], "sheenRoughnessFactor": 0.5},
     "sheenPixels", {}),
    ("KHR_materials_transmission", "KHR_materials_transmission", {"transmissionFactor": 0.8}, "transmissionPixels", {}),
    ("KHR_materials_transmission + KHR_materials_volume", "KHR_materials_transmission+volume",
     {"transmissionFactor": 0.8}, "transmissionPixels", {}),
    ("--environment neutral", None, None, "environmentPixels", {"environment": "neutral"}),
]
VOLUME = {"thicknessFactor": 0.5, "attenuationColor": [0.9, 0.6, 0.3], "attenuationDistance": 1.0}


def read_document(path):
    """The glTF JSON and, for a GLB, its BIN chunk."""
    data = path.read_bytes()
    if path.suffix.lower() != ".glb":
        return json.loads(data), None
    length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(data[20:20 + length])
    rest = data[20 + length:]
    binary = rest[8:8 + struct.unpack_from("<I", rest, 0)[0]] if rest else None
    return document, binary


def write_document(document, binary, source, target):
    """As `source` was written: a .gltf with copies of its resources beside it (the reader takes
    resources from the file's folder only), or a .glb."""
    if binary is None:
        for entry in document.get("buffers", []) + document.get("images", []):
            if "uri" in entry and not entry["uri"].startswith("data:") and not (target.parent / entry["uri"]).exists():
                shutil.copyfile(source.parent / entry["uri"], target.parent / entry["uri"])
        target.write_text(json.dumps(document))
        return
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(binary), b"BIN\0") + binary
    target.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)


def with_extension(document, extension, value):
    d = copy.deepcopy(document)
    names = [extension] if extension != "KHR_materials_transmission+volume" else ["KHR_materials_transmission",
                                                                                     "KHR_materials_volume"]
    d["extensionsUsed"] = sorted(set(d.get("extensionsUsed", [])) | set(names))
    for material in d.get("materials", []):
        extensions = material.setdefault("extensions", {})
        extensions[names[0]] = value
        if len(names) == 2:
            extensions[names[1]] = VOLUME
        if names[0] == "KHR_materials_emissive_strength" and "emissiveFactor" not in material:
            material["emissiveFactor"] = [0.1, 0.05, 0.0]
        # The diffuse texture is the base colour's, so the specular-glossiness row fetches as much;
        # its specular-glossiness texture is left out (the metallic-roughness texture is not one).
        base = material.get("pbrMetallicRoughness", {}).get("baseColorTexture")
        if names[0] == "KHR_materials_pbrSpecularGlossiness" and base:
            extensions[names[0]] = dict(value, diffuseTexture=base)
    return d


def frame_ms(scene, width, height, options):
    scene.render(width, height, 1, **options)
    return scene.stats["timesMs"]["frame"], scene.stats["stages"]["shade"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="*", type=Path)
    parser.add_argument("--build", default=str(REPOSITORY / "build" / "release"))
    parser.add_argument("--pairs", type=int, default=7)
    parser.add_argument("--size", default="1920x1080")
    args = parser.parse_args()
    sys.path.insert(0, str(Path(args.build) / "python"))
    import cuberille  # noqa: E402  (the build's package)

    width, height = (int(v) for v in args.size.split("x"))
    models = args.models or [m for m in DEFAULT_MODELS if m.exists()]
    if not models:
        sys.exit("no models: pass glTF files, or provide ../shared/data")
    print(f"| model | what | without, ms | with, ms | ratio (median of {args.pairs} pairs) | pixels counted / shaded |")
    print("|---|---|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory() as work:
        for model in models:
            document, binary = read_document(model)
            plain = cuberille.Scene(model)
            frame_ms(plain, width, height, {})  # warm: textures decoded, tables made
            for name, extension, value, counter, options in VARIANTS:
                if extension:
                    target = Path(work) / (model.stem + "-" + extension.replace("+", "-") + model.suffix)
                    write_document(with_extension(document, extension, value), binary, model, target)
                    variant = cuberille.Scene(target)
                else:
                    variant = plain
                frame_ms(variant, width, height, options)
                without, with_, ratios = [], [], []
                for _ in range(args.pairs):
                    a, _ = frame_ms(plain, width, height, {})
                    b, shade = frame_ms(variant, width, height, options)
                    without.append(a), with_.append(b), ratios.append(b / a)
                counted = f"{shade[counter]:,} / {shade['pixelsShaded']:,}" if counter else "— (applied at load)"
                print(f"| {model.name} | {name} | {statistics.median(without):.1f} | {statistics.median(with_):.1f} | "
                      f"{statistics.median(ratios):.2f}× | {counted} |", flush=True)


if __name__ == "__main__":
    main()
