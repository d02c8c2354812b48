"""The frame's scene as plain numpy data: the TOML's camera, output,
lights and environment; its meshes in world space (glTF node transforms,
then the entry's translate / rotate / scale, as specula places them:
docs/scenes.md, "Meshes"); each mesh's material as factors plus the glTF
texture slots it fills, with the decoded images.

Only what bench/scenes/gltf-frame.toml uses is read: `gltf` and `plane`
meshes, `metallic_roughness` scene materials, point and directional
lights, an environment `map`. Anything else is an error rather than a
silent difference from specula.
"""
import base64
import io
import json
import math
import os
import struct
import tomllib
from dataclasses import dataclass, field

import numpy as np
from PIL import Image

# glTF accessor component types and their numpy dtypes.
COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
             5125: np.uint32, 5126: np.float32}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


@dataclass
class Material:
    """A glTF material's factors (glTF defaults) and its texture slots:
    slot name -> (PIL image, "srgb" | "linear"). Slots follow the glTF
    names: base_color, metallic_roughness, normal, clearcoat,
    clearcoat_roughness, clearcoat_normal, sheen_color, sheen_roughness,
    specular, specular_color."""
    name: str
    base_color: tuple = (1.0, 1.0, 1.0)
    metallic: float = 1.0
    roughness: float = 1.0
    ior: float = 1.5
    specular: float = 1.0
    specular_color: tuple = (1.0, 1.0, 1.0)
    clearcoat: float = 0.0
    clearcoat_roughness: float = 0.0
    sheen_color: tuple = (0.0, 0.0, 0.0)
    sheen_roughness: float = 0.0
    normal_scale: float = 1.0
    clearcoat_normal_scale: float = 1.0
    textures: dict = field(default_factory=dict)


@dataclass
class Mesh:
    """World-space triangles: vertices (V, 12) f32 = position, normal,
    uv (glTF's, v down), tangent (xyz, w = bitangent sign); indices (T, 3)."""
    name: str
    vertices: np.ndarray
    indices: np.ndarray
    material: Material


def euler_xyz_deg(r):
    """specula's `rotate`: degrees about X, then Y, then Z (Rz Ry Rx)."""
    ax, ay, az = (math.radians(v) for v in r)
    rx = np.array([[1, 0, 0], [0, math.cos(ax), -math.sin(ax)], [0, math.sin(ax), math.cos(ax)]])
    ry = np.array([[math.cos(ay), 0, math.sin(ay)], [0, 1, 0], [-math.sin(ay), 0, math.cos(ay)]])
    rz = np.array([[math.cos(az), -math.sin(az), 0], [math.sin(az), math.cos(az), 0], [0, 0, 1]])
    return rz @ ry @ rx


def entry_matrix(entry):
    """The [[mesh]] entry's translate · rotate · scale as a 4x4 (column vectors)."""
    s = entry.get("scale", 1.0)
    s = np.array([s, s, s] if isinstance(s, (int, float)) else s, dtype=np.float64)
    m = np.eye(4)
    m[:3, :3] = euler_xyz_deg(entry.get("rotate", [0.0, 0.0, 0.0])) @ np.diag(s)
    m[:3, 3] = entry.get("translate", [0.0, 0.0, 0.0])
    return m


def quat_matrix(q):
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def node_matrix(node):
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T  # glTF is column-major
    m = np.eye(4)
    m[:3, :3] = quat_matrix(node.get("rotation", [0, 0, 0, 1])) @ np.diag(node.get("scale", [1, 1, 1]))
    m[:3, 3] = node.get("translation", [0, 0, 0])
    return m


class Gltf:
    """A .gltf or .glb file: its JSON and its buffers as bytes."""

    def __init__(self, path):
        self.dir = os.path.dirname(path)
        with open(path, "rb") as fh:
            raw = fh.read()
        glb_bin = None
        if raw[:4] == b"glTF":
            json_len = struct.unpack_from("<I", raw, 12)[0]
            self.doc = json.loads(raw[20:20 + json_len])
            off = 20 + json_len
            if off < len(raw):
                bin_len = struct.unpack_from("<I", raw, off)[0]
                glb_bin = raw[off + 8:off + 8 + bin_len]
        else:
            self.doc = json.loads(raw)
        self.buffers = [self._uri_bytes(b.get("uri")) if "uri" in b else glb_bin
                        for b in self.doc.get("buffers", [])]
        for ext in self.doc.get("extensionsRequired", []):
            raise ValueError(f"{path}: requires {ext}, which this peer does not read")

    def _uri_bytes(self, uri):
        if uri.startswith("data:"):
            return base64.b64decode(uri.split(",", 1)[1])
        with open(os.path.join(self.dir, uri), "rb") as fh:
            return fh.read()

    def view_bytes(self, index):
        bv = self.doc["bufferViews"][index]
        off = bv.get("byteOffset", 0)
        return self.buffers[bv["buffer"]][off:off + bv["byteLength"]], bv.get("byteStride")

    def accessor(self, index):
        """An accessor as a (count, width) float64 or integer array (no sparse)."""
        a = self.doc["accessors"][index]
        dtype, width = np.dtype(COMPONENT[a["componentType"]]), WIDTH[a["type"]]
        data, stride = self.view_bytes(a["bufferView"])
        off, count = a.get("byteOffset", 0), a["count"]
        elem = dtype.itemsize * width
        stride = stride or elem
        rows = np.frombuffer(data, dtype=np.uint8, count=stride * (count - 1) + elem, offset=off)
        rows = np.lib.stride_tricks.as_strided(rows, (count, elem), (stride, 1))
        out = np.ascontiguousarray(rows).view(dtype).reshape(count, width)
        if a.get("normalized") and dtype.kind in "iu":
            out = np.maximum(out / np.iinfo(dtype).max, -1.0)
        return out

    def image(self, tex_index):
        img = self.doc["images"][self.doc["textures"][tex_index]["source"]]
        if "bufferView" in img:
            data, _ = self.view_bytes(img["bufferView"])
        else:
            data = self._uri_bytes(img["uri"])
        return Image.open(io.BytesIO(data))

    def material(self, index):
        """glTF material `index` as a Material (specula's scene_material:
        the base and the clearcoat, sheen, specular and ior extensions)."""
        if index is None:
            return Material("default")
        m = self.doc["materials"][index]
        pbr = m.get("pbrMetallicRoughness", {})
        ext = m.get("extensions", {})
        cc, sh = ext.get("KHR_materials_clearcoat", {}), ext.get("KHR_materials_sheen", {})
        sp = ext.get("KHR_materials_specular", {})
        mat = Material(
            name=m.get("name", f"materials[{index}]"),
            base_color=tuple(pbr.get("baseColorFactor", [1, 1, 1, 1])[:3]),
            metallic=pbr.get("metallicFactor", 1.0), roughness=pbr.get("roughnessFactor", 1.0),
            ior=ext.get("KHR_materials_ior", {}).get("ior", 1.5),
            specular=sp.get("specularFactor", 1.0),
            specular_color=tuple(sp.get("specularColorFactor", [1, 1, 1])),
            clearcoat=cc.get("clearcoatFactor", 0.0),
            clearcoat_roughness=cc.get("clearcoatRoughnessFactor", 0.0),
            sheen_color=tuple(sh.get("sheenColorFactor", [0, 0, 0])),
            sheen_roughness=sh.get("sheenRoughnessFactor", 0.0))
        # (slot, where the texture info lives, key, encoding)
        slots = [("base_color", pbr, "baseColorTexture", "srgb"),
                 ("metallic_roughness", pbr, "metallicRoughnessTexture", "linear"),
                 ("normal", m, "normalTexture", "linear"),
                 ("clearcoat", cc, "clearcoatTexture", "linear"),
                 ("clearcoat_roughness", cc, "clearcoatRoughnessTexture", "linear"),
                 ("clearcoat_normal", cc, "clearcoatNormalTexture", "linear"),
                 ("sheen_color", sh, "sheenColorTexture", "srgb"),
                 ("sheen_roughness", sh, "sheenRoughnessTexture", "linear"),
                 ("specular", sp, "specularTexture", "linear"),
                 ("specular_color", sp, "specularColorTexture", "srgb")]
        for slot, holder, key, enc in slots:
            if key in holder:
                info = holder[key]
                if info.get("texCoord", 0) != 0 or "extensions" in info:
                    raise ValueError(f"{mat.name}: {key} uses a uv set or transform this peer does not read")
                mat.textures[slot] = (info["index"], enc)
        mat.normal_scale = m.get("normalTexture", {}).get("scale", 1.0)
        mat.clearcoat_normal_scale = cc.get("clearcoatNormalTexture", {}).get("scale", 1.0)
        return mat

    def scene_nodes(self):
        """(node, world matrix) for every node with a mesh, down the default scene."""
        doc = self.doc
        out = []

        def walk(i, parent):
            node = doc["nodes"][i]
            m = parent @ node_matrix(node)
            if "mesh" in node:
                out.append((node, m))
            for c in node.get("children", []):
                walk(c, m)

        for i in doc["scenes"][doc.get("scene", 0)]["nodes"]:
            walk(i, np.eye(4))
        return out


def uv_tangents(pos, nrm, uv, tris):
    """Per-vertex tangents along +u, bitangent sign w, [Lengyel01] as
    specula's compute_tangents, on specula's uvs (u, 1 - v): the
    bitangent then points up the picture, where a normal map's green is."""
    uv = np.stack([uv[:, 0], 1.0 - uv[:, 1]], axis=1)
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    e1, e2 = pos[b] - pos[a], pos[c] - pos[a]
    s1, s2 = uv[b] - uv[a], uv[c] - uv[a]
    det = s1[:, 0] * s2[:, 1] - s2[:, 0] * s1[:, 1]
    ok = (det != 0) & np.isfinite(det)
    sign = np.sign(det)[:, None] * ok[:, None]
    pu = (e1 * s2[:, 1:2] - e2 * s1[:, 1:2]) * sign
    pv = (e2 * s1[:, 0:1] - e1 * s2[:, 0:1]) * sign
    du, dv = np.zeros_like(pos), np.zeros_like(pos)
    for k in (a, b, c):
        np.add.at(du, k, pu)
        np.add.at(dv, k, pv)
    t = du - nrm * np.sum(nrm * du, axis=1, keepdims=True)
    length = np.linalg.norm(t, axis=1, keepdims=True)
    # A vertex without a uv direction gets any vector orthogonal to n.
    other = np.where(np.abs(nrm[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    fallback = np.cross(nrm, other)
    fallback /= np.linalg.norm(fallback, axis=1, keepdims=True)
    t = np.where(length > 1e-20, t / np.maximum(length, 1e-30), fallback)
    w = np.where(np.sum(np.cross(nrm, t) * dv, axis=1) < 0, -1.0, 1.0)
    return np.concatenate([t, w[:, None]], axis=1)


def place(pos, nrm, tan, m):
    """Vertices under the 4x4 `m`: normals by the inverse transpose,
    tangents by the linear part (w kept, flipped under a mirror)."""
    lin = m[:3, :3]
    p = pos @ lin.T + m[:3, 3]
    n = nrm @ np.linalg.inv(lin)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    t = tan[:, :3] @ lin.T
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-30)
    w = tan[:, 3:] * np.sign(np.linalg.det(lin))
    return p, n, np.concatenate([t, w], axis=1)


def pack(p, n, uv, t):
    return np.concatenate([p, n, uv, t], axis=1).astype(np.float32)


def gltf_meshes(path, entry):
    """Every primitive of the file's default scene, placed in the world."""
    g = Gltf(path)
    top = entry_matrix(entry)
    meshes, images = [], {}
    for node, m in g.scene_nodes():
        mesh = g.doc["meshes"][node["mesh"]]
        for k, prim in enumerate(mesh["primitives"]):
            if prim.get("mode", 4) != 4:
                raise ValueError(f"{path}: only TRIANGLES primitives are read")
            attr = prim["attributes"]
            pos = g.accessor(attr["POSITION"]).astype(np.float64)
            nrm = g.accessor(attr["NORMAL"]).astype(np.float64)
            uv = g.accessor(attr["TEXCOORD_0"]).astype(np.float64) if "TEXCOORD_0" in attr \
                else np.zeros((len(pos), 2))
            idx = g.accessor(prim["indices"]).reshape(-1, 3).astype(np.int64) if "indices" in prim \
                else np.arange(len(pos)).reshape(-1, 3)
            tan = g.accessor(attr["TANGENT"]).astype(np.float64) if "TANGENT" in attr \
                else uv_tangents(pos, nrm, uv, idx)
            p, n, t = place(pos, nrm, tan, top @ m)
            if np.linalg.det((top @ m)[:3, :3]) < 0:
                idx = idx[:, ::-1]  # a mirror: keep the front counter-clockwise
            mat = g.material(prim.get("material"))
            for slot, (tex, enc) in list(mat.textures.items()):
                if tex not in images:
                    images[tex] = g.image(tex)
                mat.textures[slot] = (images[tex], enc)
            name = f"{os.path.basename(path)}:{node.get('name', mesh.get('name', ''))}[{k}]"
            meshes.append(Mesh(name, pack(p, n, uv, t), idx.astype(np.uint32), mat))
    return meshes


def plane_mesh(entry, materials):
    """specula's `plane`: the XZ plane through the origin facing +Y, one
    quad per segment (only segments = [1, 1] here), uv (0, 0) to (1, 1)."""
    sx, sz = entry["plane"].get("size", [1.0, 1.0])
    if entry["plane"].get("segments", [1, 1]) != [1, 1]:
        raise ValueError("plane segments other than [1, 1] are not read")
    pos = np.array([[-sx / 2, 0, -sz / 2], [-sx / 2, 0, sz / 2], [sx / 2, 0, -sz / 2], [sx / 2, 0, sz / 2]])
    nrm = np.tile([0.0, 1.0, 0.0], (4, 1))
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    idx = np.array([[0, 1, 2], [2, 1, 3]])  # counter-clockwise seen from +Y
    tan = np.tile([0.0, 0.0, 1.0, 1.0], (4, 1))
    p, n, t = place(pos, nrm, tan, entry_matrix(entry))
    if np.linalg.det(entry_matrix(entry)[:3, :3]) < 0:
        idx = idx[:, ::-1]
    return Mesh("plane", pack(p, n, uv, t), idx.astype(np.uint32), materials[entry["material"]])


def scene_material(name, desc):
    """A `metallic_roughness` scene material as the glTF model it equals
    (docs/scenes.md, `fresnel`: the same f at metallic 0 and 1)."""
    plain = {"model", "base_color", "roughness", "metallic"}
    if desc.get("model") != "metallic_roughness" or set(desc) - plain:
        raise ValueError(f"materials.{name}: only plain metallic_roughness materials are read")
    return Material(name, base_color=tuple(desc["base_color"]), roughness=desc["roughness"],
                    metallic=desc.get("metallic", 0.0))


def load(path):
    """The scene file at `path`: a dict of camera, output, lights,
    environment map path and meshes (world space)."""
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    here = os.path.dirname(os.path.abspath(path))
    materials = {k: scene_material(k, v) for k, v in doc.get("materials", {}).items()}
    meshes = []
    for entry in doc["mesh"]:
        if "gltf" in entry:
            if "material" in entry:
                raise ValueError("a material override on a glTF mesh is not read")
            meshes += gltf_meshes(os.path.join(here, entry["gltf"]), entry)
        elif "plane" in entry:
            meshes.append(plane_mesh(entry, materials))
        else:
            raise ValueError(f"mesh kind not read by this peer: {sorted(entry)}")
    lights = []
    for light in doc.get("light", []):
        if light.get("shadows") != "pcf" or light["type"] not in ("point", "directional"):
            raise ValueError("only point and directional lights with pcf shadows are read")
        for k in ("shadow_map_size", "bias", "normal_bias", "filter_radius"):
            if k in light:
                raise ValueError(f"light.{k}: only the defaults are rendered")
        lights.append(light)
    env = doc["environment"]
    if set(env) != {"map"}:
        raise ValueError("environment: only `map` (no intensity, rotate, visible, ibl) is read")
    out = doc["output"]
    return dict(camera=doc["camera"], width=out["width"], height=out["height"],
                exposure=out.get("exposure", 0.0), tonemap=out.get("tonemap", "clamp"),
                lights=lights, env_map=os.path.join(here, env["map"]), meshes=meshes)
