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
  integer >= 0, meta an integer >= 0 (IScene; an index into metas); units (TS IScene
  requires it; Voyager reads a missing one as mm) one of TUnitType;
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
  MetallicRoughness, Zone;
- metas[] (json/meta.schema.json, meta.ts): only the keys collection, process, images,
  articles, leadArticle, audio, actions; collection and process objects; images an array
  of at least one image: uri (non-empty string) and quality (Thumb, Low, Medium, High,
  HDR) required, byteSize, width, height integers >= 1, usage one of Render, Environment,
  ARCode; articles at least one, each with only IArticle's keys and a non-empty id;
  leadArticle an integer >= 0.

Then what scanlod promises on top: one Web3D derivative per quality Thumb, Low, Medium,
High, Highest (Voyager's DerivativeList.select takes the first match), each one GLB asset
(type Model, mimeType model/gltf-binary) whose uri is a file of the item's folder, whose
byteSize is that file's size and whose numFaces is the triangle count of that GLB (its
primitives' indices) and of the report's level; the scene's meta (scenes[0].meta) holds
the collection record: titles.EN the report's title, and accession, credit, licence as
the item's manifest row says (--manifest CSV), the credit and licence also in
asset.copyright; with thumbnails, one Thumb image (the finest level's PNG: its size in
bytes, width and height) that an Image2D derivative names too; and the report's
"manifest" says the same.

Usage: check_svx.py [--manifest CSV] ITEM_DIR... ; prints one line per failed expectation and
"N passed, N failed"; exit 1 on any failure.
"""
import json
import os
import struct
import sys

passed = 0
failed = 0

DOC_KEYS = {"asset", "scene", "scenes", "nodes", "metas", "setups", "cameras", "lights", "models"}
META_KEYS = {"collection", "process", "images", "articles", "leadArticle", "audio", "actions"}
ARTICLE_KEYS = {"id", "title", "titles", "lead", "leads", "tags", "taglist", "intros", "uri", "uris",
                "mimeType", "thumbnailUri"}
IMAGE_QUALITIES = {"Thumb", "Low", "Medium", "High", "HDR"}
IMAGE_USAGES = {"Render", "Environment", "ARCode"}
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
        if "meta" in s:
            ok &= check(is_int(s["meta"], 0) and s["meta"] < len(doc.get("metas", [])),
                        f"{where}: scenes[{i}].meta indexes metas")
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
    metas = doc.get("metas", [])
    if "metas" in doc:
        ok &= check(isinstance(metas, list), f"{where}: metas is an array")
    for m, meta in enumerate(metas if isinstance(metas, list) else []):
        ok &= check_meta(meta, f"{where}: metas[{m}]")
    return bool(ok)


def check_meta(meta, where):
    if not check(isinstance(meta, dict), f"{where} is an object"):
        return False
    ok = check(set(meta) <= META_KEYS, f"{where}: only a meta's keys ({sorted(set(meta) - META_KEYS)})")
    for key in ("collection", "process"):
        if key in meta:
            ok &= check(isinstance(meta[key], dict), f"{where}: {key} is an object")
    if "images" in meta:
        images = meta["images"]
        ok &= check(isinstance(images, list) and len(images) >= 1, f"{where}: images has items")
        for i, im in enumerate(images if isinstance(images, list) else []):
            w = f"{where}.images[{i}]"
            if not check(isinstance(im, dict), f"{w} is an object"):
                ok = False
                continue
            ok &= check(is_str(im.get("uri"), 1), f"{w}: uri is a non-empty string")
            ok &= check(im.get("quality") in IMAGE_QUALITIES, f"{w}: quality is an image quality ({im.get('quality')!r})")
            for key in ("byteSize", "width", "height"):
                if key in im:
                    ok &= check(is_int(im[key], 1), f"{w}: {key} is an integer >= 1 ({im[key]!r})")
            if "usage" in im:
                ok &= check(im["usage"] in IMAGE_USAGES, f"{w}: usage is an image usage")
    if "articles" in meta:
        arts = meta["articles"]
        ok &= check(isinstance(arts, list) and len(arts) >= 1, f"{where}: articles has items")
        for i, a in enumerate(arts if isinstance(arts, list) else []):
            ok &= check(isinstance(a, dict) and set(a) <= ARTICLE_KEYS and is_str(a.get("id"), 1),
                        f"{where}.articles[{i}]: an article with an id and only an article's keys")
    if "leadArticle" in meta:
        ok &= check(is_int(meta["leadArticle"], 0), f"{where}: leadArticle is an integer >= 0")
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


def png_size(path):
    """(width, height) from a PNG's IHDR, or None."""
    data = open(path, "rb").read(24)
    if data[:8] != b"\x89PNG\r\n\x1a\n" or data[12:16] != b"IHDR":
        return None
    return struct.unpack(">II", data[16:24])


def check_meta_promises(doc, folder, where, report, row):
    """The scene's meta: the collection record and the thumbnail (module docstring)."""
    scene = doc["scenes"][doc["scene"]]
    if not check("meta" in scene, f"{where}: the scene has a meta"):
        return
    meta = doc["metas"][scene["meta"]]
    coll = meta.get("collection", {})
    man = report.get("manifest", {})
    check(coll.get("titles", {}).get("EN") == man.get("title") and man.get("title"),
          f"{where}: collection titles.EN {coll.get('titles')!r} is the report's title {man.get('title')!r}")
    if row is not None:
        check(man.get("title") == (row.get("title") or report.get("item")) or not row.get("title") or
              man.get("title") == row.get("title"), f"{where}: the title is the manifest's")
        for key in ("accession", "credit", "licence"):
            check(coll.get(key, "") == row.get(key, ""), f"{where}: collection {key} {coll.get(key)!r} is the manifest's {row.get(key)!r}")
        for key in ("credit", "licence"):
            if row.get(key):
                check(row[key] in doc["asset"].get("copyright", ""), f"{where}: asset.copyright names the {key}")
    images = meta.get("images", [])
    ders = [d for d in doc["models"][0]["derivatives"] if d["usage"] == "Image2D"]
    pngs = [f for f in os.listdir(folder) if f.endswith(".png")]
    if not pngs:
        check(not images and not ders, f"{where}: no thumbnails, no images")
        return
    if not check(len(images) == 1 and len(ders) == 1, f"{where}: one Thumb image and one Image2D derivative"):
        return
    im, asset = images[0], ders[0]["assets"][0]
    path = os.path.join(folder, im["uri"])
    if not check("/" not in im["uri"] and os.path.isfile(path), f"{where}: image {im['uri']!r} is a file of the item"):
        return
    size = png_size(path)
    check(im.get("byteSize") == os.path.getsize(path) and size == (im.get("width"), im.get("height")),
          f"{where}: image byteSize {im.get('byteSize')} and {im.get('width')}x{im.get('height')} are {im['uri']}'s ({os.path.getsize(path)}, {size})")
    finest = [d["assets"][0]["uri"] for d in doc["models"][0]["derivatives"] if d["quality"] == "Highest"]
    check(finest and im["uri"] == finest[0][:-len(".glb")] + ".png", f"{where}: the image is the finest level's thumbnail")
    check(ders[0]["quality"] == "Thumb" and asset.get("uri") == im["uri"] and asset.get("type") == "Image" and
          asset.get("mimeType") == "image/png" and asset.get("byteSize") == im.get("byteSize") and
          asset.get("imageSize") == max(size or (0, 0)), f"{where}: the Image2D derivative names that image")


def check_item(folder, manifest=None):
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
    check(all(d["usage"] in ("Web3D", "Image2D") for d in ders), f"{where}: Web3D and Image2D derivatives only")
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
    flat = [{"usage": d["usage"], "quality": d["quality"], **d["assets"][0]} for d in ders]
    in_report = [{k: v for k, v in d.items() if k != "level"} for d in man.get("derivatives", [])]
    check(in_report == flat, f"{where}: the report's manifest derivatives are the document's")
    check(all(d.get("uri") == d.get("level", "") + (".png" if d.get("usage") == "Image2D" else ".glb")
              for d in man.get("derivatives", [])), f"{where}: the report names each derivative's level")
    item = os.path.relpath(folder.rstrip("/"), os.path.dirname(os.path.dirname(folder.rstrip("/"))))
    row = None
    if manifest is not None:
        row = next((r for f, r in manifest.items() if folder.rstrip("/").endswith("/" + f)), {})
    check_meta_promises(doc, folder, where, dict(report, item=item), row)


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip().splitlines()[-3], file=sys.stderr)
        return 2
    args = argv[1:]
    manifest = None
    if args[:1] == ["--manifest"]:
        import csv
        manifest = {r["file"]: r for r in csv.DictReader(open(args[1], encoding="utf-8"))}
        args = args[2:]
    for folder in args:
        check_item(folder, manifest)
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
