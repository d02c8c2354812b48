"""What the split sum needs before the first frame, in numpy: the
Radiance map itself, its SH9 irradiance, the GGX sample sets of the
prefiltered levels, the F0·A + B (and C) albedo table and the sheen
lobe's albedo tables. The same definitions as specula's
(raster/src/envmap.rs, core/src/albedo_tables.rs, core/src/sheen.rs),
written again here from the formulas, not translated line by line.
"""
import math

import numpy as np

# -- Radiance RGBE -----------------------------------------------------


def read_rgbe(path):
    """A Radiance .hdr file as (height, width, 3) float32 linear radiance,
    row 0 at the top. Reads flat and new-style run-length scanlines."""
    with open(path, "rb") as fh:
        data = fh.read()
    pos = 0
    while True:  # header lines, up to an empty one
        end = data.index(b"\n", pos)
        line = data[pos:end]
        pos = end + 1
        if line.startswith(b"FORMAT=") and line.strip() != b"FORMAT=32-bit_rle_rgbe":
            raise ValueError(f"{path}: {line!r} is not RGBE")
        if line == b"":
            break
    end = data.index(b"\n", pos)
    axes = data[pos:end].split()
    pos = end + 1
    if axes[0] != b"-Y" or axes[2] != b"+X":
        raise ValueError(f"{path}: only -Y H +X W orientation is read")
    height, width = int(axes[1]), int(axes[3])
    buf = np.frombuffer(data, dtype=np.uint8)
    out = np.empty((height, width, 4), dtype=np.uint8)
    for y in range(height):
        if buf[pos] == 2 and buf[pos + 1] == 2 and (int(buf[pos + 2]) << 8 | int(buf[pos + 3])) == width:
            pos = _rle_scanline(buf, pos + 4, out[y], width)
        else:  # a flat scanline
            out[y] = buf[pos:pos + 4 * width].reshape(width, 4)
            pos += 4 * width
    e = out[:, :, 3].astype(np.int32)
    # What the `image` crate does (specula's decoder): m · 2^(e − 136), 0 at e = 0.
    scale = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0).astype(np.float32)
    return out[:, :, :3].astype(np.float32) * scale[:, :, None]


def _rle_scanline(buf, pos, row, width):
    """One new-style scanline: each of the 4 channels in runs."""
    for c in range(4):
        x = 0
        while x < width:
            n = int(buf[pos])
            if n > 128:  # a run of one value
                n -= 128
                row[x:x + n, c] = buf[pos + 1]
                pos += 2
            else:  # n literal values
                row[x:x + n, c] = buf[pos + 1:pos + 1 + n]
                pos += 1 + n
            x += n
    return pos


# -- Map directions and SH9 ---------------------------------------------


def uv_to_dir(u, v):
    """specula's equirect convention: centre column looks down -Z, +Y on
    top, u grows toward +X: d = (sin t sin p, cos t, -sin t cos p)."""
    phi, theta = np.broadcast_arrays((u - 0.5) * 2 * math.pi, v * math.pi)
    return np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], axis=-1)


def sh9_basis(d):
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    c1, c2 = 0.4886025, 1.0925484
    return np.stack([np.full_like(x, 0.2820948), c1 * y, c1 * z, c1 * x, c2 * x * y, c2 * y * z,
                     0.31539157 * (3 * z * z - 1), c2 * x * z, 0.5462742 * (x * x - y * y)], axis=-1)


def sh9_irradiance_over_pi(img):
    """E(n)/π in nine SH coefficients per channel (9, 3): the radiance
    projected texel by texel with each texel's exact solid angle, each
    band times the clamped cosine's Â/π = 1, 2/3, 1/4 [Ramamoorthi01]."""
    h, w, _ = img.shape
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(w) + 0.5) / w
    d = uv_to_dir(u[None, :], v[:, None])
    j = np.arange(h)
    d_omega = (2 * math.pi / w) * (np.cos(j / h * math.pi) - np.cos((j + 1) / h * math.pi))
    y = sh9_basis(d) * d_omega[:, None, None]
    coeffs = np.einsum("hwk,hwc->kc", y, img.astype(np.float64))
    band = np.array([1.0, 2 / 3, 2 / 3, 2 / 3, 0.25, 0.25, 0.25, 0.25, 0.25])
    return (coeffs * band[:, None]).astype(np.float32)


# -- The prefiltered chain's samples ------------------------------------

LEVELS = 6  # perceptual roughness k/5, k = 0..5
SAMPLES_LEVEL1 = 512  # levels 1 and 2; doubled at each coarser level, as specula's chain


def ggx_lobe_samples(alpha, count, omega_texel, top_lod):
    """`count` Hammersley samples of the GGX lobe about +z with
    n = v = r: (lx, ly, lz, source lod) of those above the horizon, the
    lod matching the sample's solid angle 1/(N p(l)) [Colbert07]."""
    i = np.arange(count)
    x1 = (i + 0.5) / count
    x2 = np.array([int(f"{k:032b}"[::-1], 2) for k in i]) / 2.0 ** 32
    a2 = alpha * alpha
    cos_h = np.sqrt((1 - x1) / (1 + (a2 - 1) * x1))
    sin_h = np.sqrt(np.maximum(1 - cos_h * cos_h, 0))
    phi = 2 * math.pi * x2
    nl = 2 * cos_h * cos_h - 1
    dd = cos_h * cos_h * (a2 - 1) + 1
    d = a2 / (math.pi * dd * dd)
    omega_s = 1 / (count * d * 0.25)
    lod = np.clip(0.5 * np.log2(omega_s / omega_texel) + 1, 0, top_lod)
    s = np.stack([2 * cos_h * sin_h * np.cos(phi), 2 * cos_h * sin_h * np.sin(phi), nl, lod], axis=1)
    return s[nl > 0].astype(np.float32)


# -- The split sum's albedo table ---------------------------------------

N_MU, N_ALPHA = 32, 32
MU_LO = 1.0 / 64.0  # the lowest view-cosine node


def hammersley(n):
    i = np.arange(n, dtype=np.uint64)
    rev = np.array([int(f"{k:032b}"[::-1], 2) for k in range(n)], dtype=np.float64)
    return (i + 0.5) / n, rev / 2.0 ** 32


def v_smith_correlated(alpha, cos_i, cos_o):
    a2 = alpha * alpha
    li = cos_o * np.sqrt(cos_i * cos_i * (1 - a2) + a2)
    lo = cos_i * np.sqrt(cos_o * cos_o * (1 - a2) + a2)
    return 0.5 / (li + lo)


def albedo_table():
    """(N_ALPHA, N_MU, 3) float32: A, B and C of specula's split sum
    (F0·A + B specular, (1 − F0)(1 − C) diffuse) on nodes at both ends,
    μ from MU_LO to 1 evenly, √α from 0 to 1 evenly; 2048 GGX samples an
    entry for A, B and 8192 cosine samples for C."""
    mu = MU_LO + (1 - MU_LO) * np.arange(N_MU) / (N_MU - 1)
    alpha = (np.arange(N_ALPHA) / (N_ALPHA - 1)) ** 2
    u1, u2 = hammersley(2048)
    out = np.zeros((N_ALPHA, N_MU, 3))
    wo = np.stack([np.sqrt(1 - mu * mu), np.zeros_like(mu), mu], axis=1)[:, None, :]
    phi = 2 * math.pi * u2
    for j, a in enumerate(alpha):
        a2 = a * a
        cos_h = np.sqrt((1 - u1) / (1 + (a2 - 1) * u1))
        sin_h = np.sqrt(np.maximum(1 - cos_h * cos_h, 0))
        h = np.stack([sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h], axis=1)[None]
        o_h = np.sum(wo * h, axis=2)
        cos_i = 2 * o_h * h[..., 2] - wo[..., 2]
        ok = (o_h > 0) & (cos_i > 0)
        mu_o = wo[..., 2]
        with np.errstate(invalid="ignore", divide="ignore"):
            weight = v_smith_correlated(a, np.maximum(cos_i, 1e-12), mu_o) * cos_i * 4 * o_h / cos_h
        weight = np.where(ok, weight, 0.0)
        w = (1 - np.clip(o_h, 0, 1)) ** 5
        out[j, :, 0] = np.sum(weight * (1 - w), axis=1) / len(u1)
        out[j, :, 1] = np.sum(weight * w, axis=1) / len(u1)
    # C(μo) = ∫ (1 − wi·h)⁵ (n·wi)/π dωi by cosine-weighted sampling.
    v1, v2 = hammersley(8192)
    r, ph = np.sqrt(v1), 2 * math.pi * v2
    wi = np.stack([r * np.cos(ph), r * np.sin(ph), np.sqrt(1 - v1)], axis=1)[None]
    hv = wi + wo
    i_h = np.sum(wi * hv, axis=2) / np.linalg.norm(hv, axis=2)
    out[:, :, 2] = np.mean((1 - np.clip(i_h, 0, 1)) ** 5, axis=1)[None, :]
    return out.astype(np.float32)


# -- The sheen lobe's albedo tables -------------------------------------

N_SHEEN_MU, N_SHEEN_R = 64, 32
SHEEN_ALPHA_MIN = 1e-3


def _l_sheen(x, t):
    mix = lambda a0, a1: a0 + (a1 - a0) * t  # noqa: E731
    a, b, c = mix(21.5473, 25.3245), mix(3.82987, 3.32435), mix(0.19823, 0.16801)
    d, e = mix(-1.97760, -1.27393), mix(-4.32054, -4.85967)
    return a / (1 + b * np.exp(c * np.log(np.maximum(x, 1e-30)))) + d * x + e


def lambda_sheen(alpha, cos_t):
    t = (1 - alpha) ** 2
    low = _l_sheen(cos_t, t)
    high = 2 * _l_sheen(0.5, t) - _l_sheen(1 - cos_t, t)
    return np.exp(np.where(cos_t < 0.5, low, high))


def sheen_tables():
    """(N_SHEEN_R, N_SHEEN_MU, 2) float32: E(μ, r), the Charlie lobe's
    directional albedo, and K(μo, r) = 2 ∫ (E(μ) − E(μo))⁺ μ dμ, on √μ and
    √r nodes at both ends (specula's SheenTable)."""
    mu_nodes = (np.arange(N_SHEEN_MU) / (N_SHEEN_MU - 1)) ** 2
    r_nodes = (np.arange(N_SHEEN_R) / (N_SHEEN_R - 1)) ** 2
    x, w = np.polynomial.legendre.leggauss(64)
    t = 0.5 * (x + 1)
    mu_i = t * t
    n_phi = 128
    phi = math.pi * (np.arange(n_phi) + 0.5) / n_phi
    s = np.sqrt(np.maximum(1 - mu_i * mu_i, 0))
    wi = np.stack([s[:, None] * np.cos(phi)[None], s[:, None] * np.sin(phi)[None],
                   np.broadcast_to(mu_i[:, None], (64, n_phi))], axis=-1)
    quad_w = (mu_i * 2 * t * 0.5 * w)[:, None] * (2 * math.pi / n_phi)
    e = np.zeros((N_SHEEN_R, N_SHEEN_MU))
    for j, r in enumerate(r_nodes):
        alpha = max(r * r, SHEEN_ALPHA_MIN)
        lam_i = lambda_sheen(alpha, mu_i)[:, None]
        for k, mo in enumerate(np.clip(mu_nodes, 1e-6, 1)):
            wo = np.array([math.sqrt(1 - mo * mo), 0, mo])
            hv = wi + wo
            sin2 = (hv[..., 0] ** 2 + hv[..., 1] ** 2) / np.sum(hv * hv, axis=-1)
            inv = 1 / alpha
            d = (2 + inv) * np.exp(np.log(np.maximum(sin2, 1e-30)) * inv * 0.5) / (2 * math.pi)
            v = 1 / ((1 + lam_i + lambda_sheen(alpha, mo)) * 4 * mu_i[:, None] * mo)
            e[j, k] = np.sum(d * v * quad_w)
    # K over the interpolated E (128-node Gauss–Legendre in t, μ = t²).
    xk, wk = np.polynomial.legendre.leggauss(128)
    tk = 0.5 * (xk + 1)
    k_tab = np.zeros_like(e)
    for j in range(N_SHEEN_R):
        e_i = np.interp(np.sqrt(tk * tk), np.sqrt(mu_nodes), e[j])  # interpolated in √μ
        for k in range(N_SHEEN_MU):
            k_tab[j, k] = 2 * np.sum(np.maximum(e_i - e[j, k], 0) * 2 * tk ** 3 * 0.5 * wk)
    return np.stack([e, k_tab], axis=-1).astype(np.float32)
