#!/usr/bin/env python3
"""Checks a published item's scene.svx.json (docs/formats.md, "scene.svx.json") against
Smithsonian Voyager's scene format and against the files it names.

The format, as Voyager's sources define it (Smithsonian/dpo-voyager, source/client/schema/:
json/document.schema.json, json/model.schema.json, json/common.schema.json and their
TypeScript twins document.ts, model.ts, common.ts), restated here for exactly the parts a
scanlod manifest uses; not a copy of those schema files:

- document: an object with only the keys asset, scene, scenes, nodes, metas, setups,
  cameras, lights, models ("additionalProperties": false), requiring asset, scene and
  scenes; nodes, setups, cameras, lights and models, when there, have at least one item;
- asset: requires type, the constant "application/si-dpo-3d.document+json", and version,
  a non-empty string; copyright a string, generator a non-empty string;
- scene: an integer >= 0 (here: an index into scenes);
- scenes[]: nodes an array of unique integers >= 0 with at least one item, setup an
  integer >= 0; units (TS IScene requires it; Voyager reads a missing one as mm) one of
  TUnitType;
- nodes[]: name a string, model/camera/light/meta integers >= 0, children unique
  integers, and never matrix together with translation, rotation or scale;
- setups[]: units one of the units;
- models[]: only the keys units, tags, visible, renderOrder, overlayMap, shadowSide,
  derivatives, translation, rotation, boundingBox, material, annotations; requires units
  and derivatives; units one of TUnitType ("mm", "cm", "m", "km", "in", "ft", "yd", "mi":
  the JSON schema also allows "inherit", TypeScript does not);
- derivatives[]: usage one of Image2D, Web3D, App3D, iOSApp3D, Print3D, Editorial3D;
  quality one of Thumb, Low, Medium, High, Highest, AR; assets an array (IDerivative
  requires all three);
- assets[]: requires uri (non-empty string) and type (Model, Geometry, Image, Texture,
  Points, Volume); mimeType a non-empty string; byteSize, numFaces, imageSize integers
  >= 1; part a non-empty string; mapType one of Color, Normal, Occlusion, Emissive,
  MetallicRoughness, Zone.

Then what scanlod promises on top: one Web3D derivative per quality Thumb, Low, Medium,
High, Highest (Voyager's DerivativeList.select takes the first match), each one GLB asset
(type Model, mimeType model/gltf-binary) whose uri is a file of the item's folder, whose
byteSize is that file's size and whose numFaces is the triangle count of that GLB (its
primitives' indices) and of the report's level; and the report's "manifest" says the same.

Usage: check_svx.py ITEM_DIR... ; prints one line per failed expectation and
"N passed, N failed"; exit 1 on any failure.
"""
import json
import os
import struct
import sys

passed = 0
failed = 0

DOC_KEYS = {"asset", "scene", "scenes", "nodes", "metas", "setups", "cameras", "lights", "models"}
MODEL_KEYS = {"units", "tags", "visible", "renderOrder", "overlayMap", "shadowSide", "derivatives",
              "translation", "rotation", "boundingBox", "material", "annotations"}
UNITS = {"mm", "cm", "m", "km", "in", "ft", "yd", "mi"}
USAGES = {"Image2D", "Web3D", "App3D", "iOSApp3D", "Print3D", "Editorial3D"}
QUALITIES = ["Thumb", "Low", "Medium", "High", "Highest", "AR"]
ASSET_TYPES = {"Model", "Geometry", "Image", "Texture", "Points", "Volume"}
MAP_TYPES = {"Color", "Normal", "Occlusion", "Emissive", "MetallicRoughness", "Zone"}
DOC_TYPE = "application/si-dpo-3d.document+json"
SCANLOD_QUALITIES = QUALITIES[:5]


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
    else:
        failed += 1
        print("FAIL: " + what, file=sys.stderr)
    return ok


def is_int(v, minimum=None):
    return isinstance(v, int) and not isinstance(v, bool) and (minimum is None or v >= minimum)


def is_str(v, min_length=0):
    return isinstance(v, str) and len(v) >= min_length


def index_array(v, unique=True):
    return (isinstance(v, list) and len(v) >= 1 and all(is_int(x, 0) for x in v) and
            (not unique or len(set(v)) == len(v)))


def check_document(doc, where):
    """Voyager's schema, restated (module docstring)."""
    if not check(isinstance(doc, dict), f"{where}: the document is an object"):
        return False
    ok = check(set(doc) <= DOC_KEYS, f"{where}: only Voyager's top-level keys ({sorted(set(doc) - DOC_KEYS)})")
    for key in ("asset", "scene", "scenes"):
        ok &= check(key in doc, f"{where}: has {key}")
    for key in ("nodes", "setups", "cameras", "lights", "models"):
        if key in doc:
            ok &= check(isinstance(doc[key], list) and len(doc[key]) >= 1, f"{where}: {key} has items")
    asset = doc.get("asset")
    if check(isinstance(asset, dict), f"{where}: asset is an object"):
        ok &= check(asset.get("type") == DOC_TYPE, f"{where}: asset.type is {DOC_TYPE}")
        ok &= check(is_str(asset.get("version"), 1), f"{where}: asset.version is a non-empty string")
        if "copyright" in asset:
            ok &= check(is_str(asset["copyright"]), f"{where}: asset.copyright is a string")
        if "generator" in asset:
            ok &= check(is_str(asset["generator"], 1), f"{where}: asset.generator is a non-empty string")
    else:
        ok = False
    scenes, nodes = doc.get("scenes", []), doc.get("nodes", [])
    setups, models = doc.get("setups", []), doc.get("models", [])
    ok &= check(isinstance(scenes, list) and all(isinstance(s, dict) for s in scenes), f"{where}: scenes are objects")
    ok &= check(is_int(doc.get("scene"), 0) and doc.get("scene") < len(scenes), f"{where}: scene indexes scenes")
    for i, s in enumerate(scenes if isinstance(scenes, list) else []):
        if not isinstance(s, dict):
            continue
        if "nodes" in s:
            ok &= check(index_array(s["nodes"]) and all(n < len(nodes) for n in s["nodes"]),
                        f"{where}: scenes[{i}].nodes are unique node indices")
        if "setup" in s:
            ok &= check(is_int(s["setup"], 0) and s["setup"] < len(setups), f"{where}: scenes[{i}].setup indexes setups")
        ok &= check(s.get("units") in UNITS, f"{where}: scenes[{i}].units is a unit ({s.get('units')!r})")
    for i, n in enumerate(nodes if isinstance(nodes, list) else []):
        if not check(isinstance(n, dict), f"{where}: nodes[{i}] is an object"):
            ok = False
            continue
        if "name" in n:
            ok &= check(is_str(n["name"]), f"{where}: nodes[{i}].name is a string")
        for key, table in (("model", models), ("camera", doc.get("cameras", [])),
                           ("light", doc.get("lights", [])), ("meta", doc.get("metas", []))):
            if key in n:
                ok &= check(is_int(n[key], 0) and n[key] < len(table), f"{where}: nodes[{i}].{key} indexes {key}s")
        if "children" in n:
            ok &= check(index_array(n["children"]), f"{where}: nodes[{i}].children are unique indices")
        ok &= check(not ("matrix" in n and any(k in n for k in ("translation", "rotation", "scale"))),
                    f"{where}: nodes[{i}] has not both matrix and TRS")
    for i, s in enumerate(setups if isinstance(setups, list) else []):
        if check(isinstance(s, dict), f"{where}: setups[{i}] is an object") and "units" in s:
            ok &= check(s["units"] in UNITS, f"{where}: setups[{i}].units is a unit")
    for m, model in enumerate(models if isinstance(models, list) else []):
        ok &= check_model(model, f"{where}: models[{m}]")
    return bool(ok)


def check_model(model, where):
    if not check(isinstance(model, dict), f"{where} is an object"):
        return False
    ok = check(set(model) <= MODEL_KEYS, f"{where}: only a model's keys ({sorted(set(model) - MODEL_KEYS)})")
    ok &= check(model.get("units") in UNITS, f"{where}: units is a unit ({model.get('units')!r})")
    derivatives = model.get("derivatives")
    if not check(isinstance(derivatives, list), f"{where}: derivatives is an array"):
        return False
    for d, der in enumerate(derivatives):
        w = f"{where}.derivatives[{d}]"
        if not check(isinstance(der, dict), f"{w} is an object"):
            ok = False
            continue
        ok &= check(der.get("usage") in USAGES, f"{w}: usage is one of Voyager's ({der.get('usage')!r})")
        ok &= check(der.get("quality") in QUALITIES, f"{w}: quality is one of Voyager's ({der.get('quality')!r})")
        assets = der.get("assets")
        if not check(isinstance(assets, list), f"{w}: assets is an array"):
            ok = False
            continue
        for a, asset in enumerate(assets):
            ok &= check_asset(asset, f"{w}.assets[{a}]")
    return bool(ok)


def check_asset(asset, where):
    if not check(isinstance(asset, dict), f"{where} is an object"):
        return False
    ok = check(is_str(asset.get("uri"), 1), f"{where}: uri is a non-empty string")
    ok &= check(asset.get("type") in ASSET_TYPES, f"{where}: type is one of Voyager's ({asset.get('type')!r})")
    for key in ("mimeType", "part"):
        if key in asset:
            ok &= check(is_str(asset[key], 1), f"{where}: {key} is a non-empty string")
    for key in ("byteSize", "numFaces", "imageSize"):
        if key in asset:
            ok &= check(is_int(asset[key], 1), f"{where}: {key} is an integer >= 1 ({asset[key]!r})")
    if "mapType" in asset:
        ok &= check(asset["mapType"] in MAP_TYPES, f"{where}: mapType is one of Voyager's")
    return bool(ok)


def glb_triangles(path):
    """Triangles of a GLB: its TRIANGLES primitives' indices (compressed ones keep the
    accessor counts of the decoded data)."""
    data = open(path, "rb").read()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF" or version != 2 or length != len(data):
        return None
    chunk_length, chunk_type = struct.unpack_from("<II", data, 12)
    if chunk_type != 0x4E4F534A:
        return None
    gltf = json.loads(data[20:20 + chunk_length])
    total = 0
    for mesh in gltf.get("meshes", []):
        for prim in mesh.get("primitives", []):
            if prim.get("mode", 4) != 4:
                return None
            if "indices" in prim:
                total += gltf["accessors"][prim["indices"]]["count"] // 3
            else:
                total += gltf["accessors"][prim["attributes"]["POSITION"]]["count"] // 3
    return total


def check_item(folder):
    where = os.path.join(os.path.basename(os.path.dirname(folder.rstrip("/"))), os.path.basename(folder.rstrip("/")))
    try:
        doc = json.load(open(os.path.join(folder, "scene.svx.json")))
    except (OSError, ValueError) as e:
        check(False, f"{where}: scene.svx.json reads as JSON ({e})")
        return
    if not check_document(doc, where):
        return
    report = json.load(open(os.path.join(folder, "report.json")))["stages"]["export"]
    levels = {lv["name"]: lv for lv in report["levels"]}
    models = doc.get("models", [])
    if not check(len(models) == 1, f"{where}: one model"):
        return
    ders = models[0]["derivatives"]
    web = [d for d in ders if d["usage"] == "Web3D"]
    qualities = [d["quality"] for d in web]
    check(sorted(qualities, key=QUALITIES.index) == SCANLOD_QUALITIES,
          f"{where}: one Web3D derivative per quality {SCANLOD_QUALITIES} ({qualities})")
    faces_of_quality = []
    for d in web:
        w = f"{where} {d['quality']}"
        if not check(len(d["assets"]) == 1, f"{w}: one asset"):
            continue
        a = d["assets"][0]
        check(a["type"] == "Model" and a.get("mimeType") == "model/gltf-binary", f"{w}: a GLB model asset")
        uri = a["uri"]
        path = os.path.join(folder, uri)
        if not check("/" not in uri and "\\" not in uri and ":" not in uri and not uri.startswith(".") and
                     os.path.isfile(path), f"{w}: uri {uri!r} is a file of the item's folder"):
            continue
        check(a.get("byteSize") == os.path.getsize(path),
              f"{w}: byteSize {a.get('byteSize')} is {uri}'s size {os.path.getsize(path)}")
        tri = glb_triangles(path)
        check(a.get("numFaces") == tri, f"{w}: numFaces {a.get('numFaces')} is {uri}'s triangle count {tri}")
        name = uri[:-len(".glb")]
        check(name in levels and levels[name].get("file") == name and levels[name]["triangles"] == a.get("numFaces"),
              f"{w}: numFaces is the report's triangles of level {name}")
        faces_of_quality.append(a.get("numFaces", 0))
    check(faces_of_quality == sorted(faces_of_quality), f"{where}: finer qualities have no fewer faces {faces_of_quality}")
    man = report.get("manifest", {})
    check(man.get("file") == "scene.svx.json" and man.get("units") == models[0]["units"],
          f"{where}: the report names the manifest and its units")
    flat = [{"usage": d["usage"], "quality": d["quality"], **{k: d["assets"][0].get(k) for k in
            ("uri", "type", "mimeType", "byteSize", "numFaces")}} for d in ders]
    in_report = [{k: v for k, v in d.items() if k != "level"} for d in man.get("derivatives", [])]
    check(in_report == flat, f"{where}: the report's manifest derivatives are the document's")
    check(all(d.get("uri") == d.get("level", "") + ".glb" for d in man.get("derivatives", [])),
          f"{where}: the report names each derivative's level")


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip().splitlines()[-3], file=sys.stderr)
        return 2
    for folder in argv[1:]:
        check_item(folder)
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
