"""The frame in OpenGL 3.3 (moderngl) the way a forward GPU engine draws
it: per frame the sun's orthographic depth map, the point light's six
cube-face depth maps (one 3 x 2 atlas), then the main pass (opaque
meshes front to back, one shader variant per material, depth tested),
the map behind them and the tone map in the same fragment programs.

Everything the frames read but do not change is built here at load:
textures and their mipmaps, the prefiltered cube chain (GL passes), the
albedo and sheen tables, SH9 (numpy, tables.py), the vertex buffers.
"""
import ctypes
import math
import os

import moderngl
import numpy as np

import tables

HERE = os.path.dirname(os.path.abspath(__file__))
MAP_SIZE = 1024         # shadow_map_size's default
BIAS = 1.0              # texels
NORMAL_BIAS = 1.0       # texels, times 1 + the filter radius
FILTER_RADIUS = 1.5     # texels
PCF_REACH = FILTER_RADIUS + 2.0  # texels a PCF lookup may read from its centre (specula's reach)
CUBE_NEAR = 0.05        # the point light's depth near plane (world units)
PREFILTER_SIZE = 256    # the mirror level's face side; each level halves it
# Texture units: the shared ones, then one per material slot.
UNIT = {"dfg": 0, "sheen_lut": 1, "prefiltered": 2, "sun_shadow": 3, "point_shadow": 4, "env": 5}
SLOTS = ["base_color", "metallic_roughness", "normal", "clearcoat", "clearcoat_roughness",
         "clearcoat_normal", "sheen_color", "sheen_roughness", "specular", "specular_color"]
UNIT.update({slot: 6 + k for k, slot in enumerate(SLOTS)})
GL_SRGB8, GL_SRGB8_ALPHA8 = 0x8C41, 0x8C43
GL_TEXTURE_CUBE_MAP_SEAMLESS = 0x884F


def source(name):
    with open(os.path.join(HERE, "shaders", name)) as fh:
        return fh.read()


def program(ctx, vert, frag, defines=()):
    """A program from shaders/; `frag` gets the defines and common.glsl."""
    head = "#version 330 core\n" + "".join(f"#define {d}\n" for d in defines) + source("common.glsl")
    return ctx.program(vertex_shader=source(vert), fragment_shader=head + source(frag))


def normalize(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def gl_mat(m):
    """A row-major 4x4 as GLSL's column-major bytes."""
    return np.ascontiguousarray(np.asarray(m, dtype=np.float32).T).tobytes()


class RawGl:
    """The few GL calls moderngl does not expose (uploading a cube map's
    mip levels), through EGL's function pointers."""

    def __init__(self):
        egl = ctypes.CDLL("libEGL.so.1")
        egl.eglGetProcAddress.restype = ctypes.c_void_p
        egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
        u, i, p = ctypes.c_uint, ctypes.c_int, ctypes.c_void_p

        def fn(name, *args):
            return ctypes.CFUNCTYPE(None, *args)(egl.eglGetProcAddress(name.encode()))

        self.active_texture = fn("glActiveTexture", u)
        self.bind_texture = fn("glBindTexture", u, u)
        self.pixel_store = fn("glPixelStorei", u, i)
        self.tex_sub_image_2d = fn("glTexSubImage2D", u, i, i, i, i, i, u, u, p)

    def upload_cube_level(self, ctx, cube, face, level, rgba):
        """`rgba` (n, n, 4) float32, row 0 at t = 0, into face `face` (GL
        order +X, −X, +Y, −Y, +Z, −Z) at mip `level` of `cube`."""
        data = np.ascontiguousarray(rgba, dtype=np.float32)
        self.active_texture(0x84C0 + ctx.default_texture_unit)  # GL_TEXTURE0 + unit
        self.bind_texture(0x8513, cube.glo)  # GL_TEXTURE_CUBE_MAP
        self.pixel_store(0x0CF5, 4)  # GL_UNPACK_ALIGNMENT
        n = data.shape[0]
        self.tex_sub_image_2d(0x8515 + face, level, 0, 0, n, n, 0x1908, 0x1406,  # GL_RGBA, GL_FLOAT
                              data.ctypes.data_as(ctypes.c_void_p))


# -- Matrices ------------------------------------------------------------


def camera_basis(cam):
    eye = np.array(cam["eye"], dtype=np.float64)
    forward = normalize(np.array(cam["target"]) - eye)
    right = normalize(np.cross(forward, cam.get("up", [0.0, 1.0, 0.0])))
    return eye, forward, right, np.cross(right, forward)


def view_proj(cam, aspect):
    """GL's clip from world for specula's camera (same view, fov_y, near, far)."""
    eye, f, r, u = camera_basis(cam)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = r, u, -f
    view[:3, 3] = -view[:3, :3] @ eye
    n, fa = cam["near"], cam["far"]
    t = 1.0 / math.tan(math.radians(cam["fov_y"]) / 2)
    proj = np.zeros((4, 4))
    proj[0, 0], proj[1, 1] = t / aspect, t
    proj[2, 2], proj[2, 3] = (fa + n) / (n - fa), 2 * fa * n / (n - fa)
    proj[3, 2] = -1.0
    return proj @ view


def up_for(axis):
    return np.array([0.0, 1.0, 0.0]) if abs(axis[1]) < 0.9 else np.array([0.0, 0.0, 1.0])


def sun_map(to_light, lo, hi, cam, aspect):
    """The directional light's orthographic map as specula fits it
    (raster/src/shadow_pass/fit.rs): across the light, the scene's bounds
    cut to the view frustum out to the farthest scene corner; along it,
    the whole scene; square texels with a margin for the filter. Returns
    (world -> clip matrix, axis, texel, near, span)."""
    axis = -normalize(to_light)
    right = normalize(np.cross(axis, up_for(axis)))
    up = np.cross(right, axis)
    basis = np.stack([right, up, axis])
    corners = np.array([[x, y, z] for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])])
    light = corners @ basis.T
    llo, lhi = light.min(axis=0), light.max(axis=0)
    eye, forward, cright, cup = camera_basis(cam)
    far = max(0.0, float(((corners - eye) @ forward).max()))
    if far > 0.0:
        tan_y = math.tan(math.radians(cam["fov_y"]) / 2)
        tan_x = tan_y * aspect
        pts = [eye + (forward + cright * (sx * tan_x) + cup * (sy * tan_y)) * d
               for d in (far * 1e-4, far) for sx in (-1, 1) for sy in (-1, 1)]
        fl = np.array(pts) @ basis.T
        x0, x1 = max(llo[0], fl[:, 0].min()), min(lhi[0], fl[:, 0].max())
        y0, y1 = max(llo[1], fl[:, 1].min()), min(lhi[1], fl[:, 1].max())
        if x0 < x1 and y0 < y1:
            llo[0], lhi[0], llo[1], lhi[1] = x0, x1, y0, y1
    diag = float(np.linalg.norm(hi - lo))
    extent = max(lhi[0] - llo[0], lhi[1] - llo[1], diag * 1e-6)
    margin = math.ceil(PCF_REACH) + 1.0
    texel = extent / max(MAP_SIZE - 2 * margin, 1.0)
    half = 0.5 * texel * MAP_SIZE
    cx, cy = 0.5 * (llo[0] + lhi[0]), 0.5 * (llo[1] + lhi[1])
    pad = 0.01 * (lhi[2] - llo[2]) + diag * 1e-4
    near, span = llo[2] - pad, (lhi[2] - llo[2]) + 2 * pad
    clip = np.array([[*(right / half), -cx / half],
                     [*(up / half), -cy / half],
                     [*(axis * 2 / span), -2 * near / span - 1],
                     [0, 0, 0, 1]])
    return clip, axis, texel, near, span


CUBE_AXES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64)


def cube_faces(pos):
    """The point light's six face maps, each a little over 90° so that a
    filter near a face's edge stays in the face (specula's cube_faces):
    world -> clip with w = depth along the face's axis and an infinite
    far plane. Returns (six matrices, texel at unit depth)."""
    margin = min(math.ceil(PCF_REACH), MAP_SIZE / 4)
    tan_half = MAP_SIZE / (MAP_SIZE - 2 * margin)
    mats = []
    for axis in CUBE_AXES:
        right = normalize(np.cross(axis, up_for(axis)))
        up = np.cross(right, axis)
        view = np.eye(4)
        view[0, :3], view[1, :3], view[2, :3] = right, up, axis
        view[:3, 3] = -view[:3, :3] @ pos
        proj = np.array([[1 / tan_half, 0, 0, 0], [0, 1 / tan_half, 0, 0],
                         [0, 0, 1, -2 * CUBE_NEAR], [0, 0, 1, 0]])
        mats.append(proj @ view)
    return mats, 2 * tan_half / MAP_SIZE


# -- The renderer --------------------------------------------------------


def material_uniforms(prog, mat):
    """The material's factors as the uniforms `prog` has (written before
    each draw: materials of one variant share its program)."""
    r0 = 1.0 if mat.ior == 0 else ((mat.ior - 1) / (mat.ior + 1)) ** 2
    values = dict(u_base_color=mat.base_color, u_metallic=mat.metallic, u_roughness=mat.roughness,
                  u_r0=r0, u_specular=mat.specular, u_specular_color=mat.specular_color,
                  u_clearcoat=mat.clearcoat, u_clearcoat_roughness=mat.clearcoat_roughness,
                  u_sheen_color=mat.sheen_color, u_sheen_roughness=mat.sheen_roughness,
                  u_normal_scale=mat.normal_scale, u_coat_normal_scale=mat.clearcoat_normal_scale)
    return [(prog[k], v) for k, v in values.items() if k in prog]


def material_defines(mat):
    """The shader variant of a material: its layers and its textures."""
    flags = {"base_color": "BASE_TEX", "metallic_roughness": "MR_TEX", "normal": "NORMAL_TEX",
             "clearcoat": "COAT_TEX", "clearcoat_roughness": "COAT_ROUGH_TEX",
             "clearcoat_normal": "COAT_NORMAL_TEX", "sheen_color": "SHEEN_COLOR_TEX",
             "sheen_roughness": "SHEEN_ROUGH_TEX", "specular": "SPEC_TEX", "specular_color": "SPEC_COLOR_TEX"}
    d = [flags[s] for s in SLOTS if s in mat.textures]
    coat = mat.clearcoat > 0
    if coat:
        d.append("COAT")
        if "clearcoat_normal" in mat.textures or "normal" in mat.textures:
            d.append("COAT_OWN_NORMAL")
    else:  # a layer off in the material is off in every pixel (its textures unread)
        d = [x for x in d if not x.startswith("COAT")]
    if max(mat.sheen_color) > 0:
        d.append("SHEEN")
    else:
        d = [x for x in d if not x.startswith("SHEEN")]
    return tuple(d)


class Renderer:
    def __init__(self, ctx, sc):
        self.ctx, self.sc = ctx, sc
        self.w, self.h = sc["width"], sc["height"]
        self.aspect = self.w / self.h
        self.raw = RawGl()
        ctx.enable_direct(GL_TEXTURE_CUBE_MAP_SEAMLESS)
        self._lights()
        self._environment()
        self._meshes()
        self._targets()

    # -- load --

    def _lights(self):
        sun = [l for l in self.sc["lights"] if l["type"] == "directional"]
        point = [l for l in self.sc["lights"] if l["type"] == "point"]
        if len(sun) != 1 or len(point) != 1:
            raise ValueError("this peer renders one directional and one point light")
        self.sun_to_light = -normalize(sun[0]["direction"])
        self.sun_irradiance = np.array(sun[0]["irradiance"], dtype=np.float64)
        self.point_pos = np.array(point[0]["position"], dtype=np.float64)
        self.point_intensity = np.array(point[0]["intensity"], dtype=np.float64)

    def _environment(self):
        ctx = self.ctx
        img = tables.read_rgbe(self.sc["env_map"])
        self.sh = tables.sh9_irradiance_over_pi(img)
        h, w, _ = img.shape
        env = ctx.texture((w, h), 3, np.ascontiguousarray(img, dtype=np.float32).tobytes(), dtype="f4")
        env.build_mipmaps()
        env.repeat_x, env.repeat_y = True, False
        self.env = env
        top_lod = math.floor(math.log2(max(w, h)))
        self.prefiltered = self._prefilter(env, 4 * math.pi / (w * h), top_lod)
        dfg = tables.albedo_table()
        self.dfg = ctx.texture((dfg.shape[1], dfg.shape[0]), 3, dfg.tobytes(), dtype="f4")
        sheen = tables.sheen_tables()
        self.sheen_lut = ctx.texture((sheen.shape[1], sheen.shape[0]), 2, sheen.tobytes(), dtype="f4")
        for t in (self.dfg, self.sheen_lut):
            t.filter = (moderngl.LINEAR, moderngl.LINEAR)
            t.repeat_x = t.repeat_y = False

    def _prefilter(self, env, omega_texel, top_lod):
        """The chain in a cube map: level k at perceptual roughness k/5,
        faces PREFILTER_SIZE >> k; 512 GGX samples a texel at levels 1
        and 2, doubled at each coarser level (specula's counts)."""
        ctx = self.ctx
        prog = program(ctx, "fullscreen.vert", "prefilter.frag")
        prog["t_env"], prog["t_samples"], prog["u_depth"] = 0, 1, 0.0
        vao = ctx.vertex_array(prog, [])
        cube = ctx.texture_cube((PREFILTER_SIZE, PREFILTER_SIZE), 4, dtype="f2")
        cube.build_mipmaps(0, tables.LEVELS - 1)  # allocates levels 1..5, overwritten below
        env.use(0)
        for k in range(tables.LEVELS):
            n = PREFILTER_SIZE >> k
            if k == 0:
                count = 0
            else:
                alpha = max((k / (tables.LEVELS - 1)) ** 2, 1e-3)
                count = tables.SAMPLES_LEVEL1 << max(k - 2, 0)
                s = tables.ggx_lobe_samples(alpha, count, omega_texel, top_lod)
                samples = ctx.texture((len(s), 1), 4, s.tobytes(), dtype="f4")
                samples.filter = (moderngl.NEAREST, moderngl.NEAREST)
                samples.use(1)
                count = len(s)
            target = ctx.texture((n, n), 4, dtype="f4")
            fbo = ctx.framebuffer([target])
            fbo.use()
            prog["u_count"], prog["u_size"] = count, float(n)
            if count:
                prog["u_alpha"] = alpha
            for face in range(6):
                prog["u_face"] = face
                vao.render(moderngl.TRIANGLES, vertices=3)
                rgba = np.frombuffer(fbo.read(components=4, dtype="f4"), dtype=np.float32).reshape(n, n, 4)
                self.raw.upload_cube_level(ctx, cube, face, k, rgba)
            fbo.release()
            target.release()
            if count:
                samples.release()
        cube.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        return cube

    def _texture(self, image, encoding, channels):
        """A material image as GL sees a glTF texture: 8-bit, sRGB-decoded
        by the sampler where the slot is a colour, mipmapped, repeat."""
        key = (id(image), encoding, channels)
        if key not in self._textures:
            img = image.convert("RGBA" if channels == 4 else "RGB")
            fmt = (GL_SRGB8_ALPHA8 if channels == 4 else GL_SRGB8) if encoding == "srgb" else None
            t = self.ctx.texture(img.size, channels, img.tobytes(), internal_format=fmt)
            t.build_mipmaps()  # LINEAR_MIPMAP_LINEAR: trilinear
            self._textures[key] = t
        return self._textures[key]

    def _meshes(self):
        ctx = self.ctx
        self._textures, self._programs = {}, {}
        eye = np.array(self.sc["camera"]["eye"])
        draws = []
        for m in self.sc["meshes"]:
            defines = material_defines(m.material)
            prog = self._programs.get(defines)
            if prog is None:
                prog = program(ctx, "scene.vert", "pbr.frag", defines)
                for name, unit in UNIT.items():
                    if f"t_{name}" in prog:
                        prog[f"t_{name}"] = unit
                self._programs[defines] = prog
            attrs = [("in_pos", 3), ("in_nrm", 3), ("in_uv", 2), ("in_tan", 4)]
            fmt = " ".join(f"{n}f" if a in prog else f"{4 * n}x" for a, n in attrs)
            names = [a for a, _ in attrs if a in prog]
            vao = ctx.vertex_array(prog, [(ctx.buffer(m.vertices.tobytes()), fmt, *names)],
                                   ctx.buffer(m.indices.tobytes()))
            # specular and sheen roughness are read in alpha (specula's four-channel maps)
            textures = [(self._texture(img, enc, 4 if slot in ("specular", "sheen_roughness") else 3),
                         UNIT[slot]) for slot, (img, enc) in m.material.textures.items() if f"t_{slot}" in prog]
            # Front to back, so early depth tests reject hidden fragments;
            # the floor, behind everything, comes last.
            dist = np.linalg.norm(m.vertices[:, :3].mean(axis=0) - eye)
            big = np.ptp(m.vertices[:, :3], axis=0).max() > 10
            draws.append(((big, dist), (prog, vao, material_uniforms(prog, m.material), textures)))
        draws.sort(key=lambda d: d[0])
        self.draws = [d for _, d in draws]
        # One buffer of every triangle for the depth passes.
        pos = np.concatenate([m.vertices[:, :3] for m in self.sc["meshes"]])
        base = np.cumsum([0] + [len(m.vertices) for m in self.sc["meshes"]])[:-1]
        idx = np.concatenate([m.indices + b for m, b in zip(self.sc["meshes"], base)]).astype(np.uint32)
        self.bounds = (pos.min(axis=0).astype(np.float64), pos.max(axis=0).astype(np.float64))
        self.depth_prog = program(ctx, "depth.vert", "depth.frag")
        self.depth_vao = ctx.vertex_array(self.depth_prog, [(ctx.buffer(pos.tobytes()), "3f", "in_pos")],
                                          ctx.buffer(idx.tobytes()))
        self.bg_prog = program(ctx, "fullscreen.vert", "background.frag")
        self.bg_vao = ctx.vertex_array(self.bg_prog, [])

    def _targets(self):
        ctx = self.ctx
        self.sun_depth = ctx.depth_texture((MAP_SIZE, MAP_SIZE))
        self.atlas = ctx.depth_texture((3 * MAP_SIZE, 2 * MAP_SIZE))
        for t in (self.sun_depth, self.atlas):
            t.compare_func = "<="  # lit where the reference is at or before the stored depth
            t.filter = (moderngl.LINEAR, moderngl.LINEAR)  # bilinear comparisons
            t.repeat_x = t.repeat_y = False
        self.sun_fbo = ctx.framebuffer(depth_attachment=self.sun_depth)
        self.atlas_fbo = ctx.framebuffer(depth_attachment=self.atlas)
        self.color = ctx.renderbuffer((self.w, self.h), 4, dtype="f1")
        self.fbo = ctx.framebuffer([self.color], ctx.depth_renderbuffer((self.w, self.h)))
        cam = self.sc["camera"]
        self.viewproj = view_proj(cam, self.aspect)
        exposure_scale = 2.0 ** self.sc["exposure"]
        eye, forward, right, up = camera_basis(cam)
        tan_y = math.tan(math.radians(cam["fov_y"]) / 2)
        for prog in self._programs.values():
            prog["u_viewproj"].write(gl_mat(self.viewproj))
            for name, value in dict(u_eye=eye, u_exposure_scale=exposure_scale, u_bias=BIAS,
                                    u_normal_bias=NORMAL_BIAS, u_filter_radius=FILTER_RADIUS,
                                    u_sun_to_light=self.sun_to_light, u_sun_irradiance=self.sun_irradiance,
                                    u_point_pos=self.point_pos, u_point_intensity=self.point_intensity,
                                    u_sun_texel_uv=(1 / MAP_SIZE, 1 / MAP_SIZE),
                                    u_face_texel_uv=(1 / (3 * MAP_SIZE), 1 / (2 * MAP_SIZE)),
                                    u_face_near=CUBE_NEAR).items():
                if name in prog:
                    prog[name].value = tuple(value) if isinstance(value, np.ndarray) else value
            if "u_sh" in prog:
                prog["u_sh"].write(self.sh.astype(np.float32).tobytes())
        bg = self.bg_prog
        bg["t_env"], bg["u_depth"] = UNIT["env"], 1.0
        bg["u_forward"].value, bg["u_right"].value, bg["u_up"].value = tuple(forward), tuple(right), tuple(up)
        bg["u_tan"].value = (tan_y * self.aspect, tan_y)
        bg["u_size"].value = (float(self.w), float(self.h))
        bg["u_exposure_scale"].value = exposure_scale

    # -- per frame --

    def shadow_setup(self):
        """Fit the maps to the scene and view (every frame, as specula
        does), and hand them to the programs."""
        cam = self.sc["camera"]
        sun_clip, axis, texel, near, span = sun_map(self.sun_to_light, *self.bounds, cam, self.aspect)
        faces, face_texel = cube_faces(self.point_pos)
        for prog in self._programs.values():
            prog["u_sun_clip"].write(gl_mat(sun_clip))
            prog["u_sun_axis"].value = tuple(axis)
            prog["u_sun_texel"].value = texel
            prog["u_sun_near"].value = near
            prog["u_sun_span"].value = span
            prog["u_face_clip"].write(b"".join(gl_mat(m) for m in faces))
            prog["u_face_texel"].value = face_texel
        return sun_clip, faces

    def shadow_passes(self, sun_clip, faces):
        ctx = self.ctx
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.CULL_FACE)  # both faces cast (the floor is open)
        ctx.depth_func = "<"
        self.sun_fbo.use()
        self.sun_fbo.clear(depth=1.0)
        self.depth_prog["u_viewproj"].write(gl_mat(sun_clip))
        self.depth_vao.render(moderngl.TRIANGLES)
        fbo = self.atlas_fbo
        fbo.scissor = None
        fbo.use()
        fbo.clear(depth=1.0)
        for k, m in enumerate(faces):
            tile = ((k % 3) * MAP_SIZE, (k // 3) * MAP_SIZE, MAP_SIZE, MAP_SIZE)
            fbo.viewport = fbo.scissor = tile
            fbo.use()
            self.depth_prog["u_viewproj"].write(gl_mat(m))
            self.depth_vao.render(moderngl.TRIANGLES)
        fbo.scissor = None
        fbo.viewport = (0, 0, 3 * MAP_SIZE, 2 * MAP_SIZE)

    def main_pass(self, query=None):
        """The meshes (inside `query` if given), then the map behind them."""
        ctx = self.ctx
        self.fbo.use()
        self.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        ctx.front_face, ctx.cull_face, ctx.depth_func = "ccw", "back", "<"
        self.dfg.use(UNIT["dfg"])
        self.sheen_lut.use(UNIT["sheen_lut"])
        self.prefiltered.use(UNIT["prefiltered"])
        self.sun_depth.use(UNIT["sun_shadow"])
        self.atlas.use(UNIT["point_shadow"])
        self.env.use(UNIT["env"])
        if query is not None:
            with query:
                self.draw_meshes()
        else:
            self.draw_meshes()
        ctx.depth_func = "<="  # the map where the depth buffer kept its clear value
        self.bg_vao.render(moderngl.TRIANGLES, vertices=3)

    def draw_meshes(self):
        for prog, vao, uniforms, textures in self.draws:
            for uniform, value in uniforms:
                uniform.value = value
            for tex, unit in textures:
                tex.use(unit)
            vao.render(moderngl.TRIANGLES)

    def frame(self):
        """One timed frame: the seven depth passes, the main pass, finish."""
        sun_clip, faces = self.shadow_setup()
        self.shadow_passes(sun_clip, faces)
        self.main_pass()
        self.ctx.finish()

    def image(self):
        """The last frame, (h, w, 3) uint8, row 0 at the top."""
        data = self.fbo.read(components=3, dtype="f1")
        return np.frombuffer(data, dtype=np.uint8).reshape(self.h, self.w, 3)[::-1].copy()

    def fragments_shaded(self):
        """Fragments of the meshes that passed the depth test in one main pass."""
        q = self.ctx.query(samples=True)
        self.main_pass(query=q)
        self.ctx.finish()
        return int(q.samples)
