"""Scenes for the renders: rows of spheres, a camera, lights, a procedural environment.

Everything returns plain Mitsuba scene dicts (``mi.load_dict``), so a user can add shapes or
swap the lights. Needs a Mitsuba variant set (``mi.set_variant``) for the functions that build
Mitsuba objects (:func:`environment`, :func:`render`).

The default lighting is a dim procedural sky (a horizon gradient with two bright softbox
panels, :func:`environment_image`) plus one directional light from the upper left, so that both
the highlight and the glossy reflection of the panels show how rough a sphere is — the setup of
the seed's sphere rows (Figs. 2.7, 3.13–3.17).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..io import atomic_path

#: The lights :func:`sphere_row` can set up.
EMITTERS = ("sky+sun", "sky", "sun", "constant")

__all__ = [
    "EMITTERS",
    "block_mean",
    "environment",
    "environment_image",
    "image_difference",
    "render",
    "save_png",
    "save_rows",
    "sphere_row",
    "to_srgb",
]


def environment_image(width: int = 256) -> np.ndarray:
    """A lat-long (equirectangular) sky [linear RGB], ``(width/2, width, 3)`` float32: a soft
    horizon gradient and two rectangular softboxes (the bright features glossy spheres mirror)."""
    if width < 16 or width % 2:
        raise ValueError(f"width must be an even integer >= 16, got {width!r}")
    h = width // 2
    v = (np.arange(h) + 0.5) / h  # 0 = zenith, 1 = nadir
    u = (np.arange(width) + 0.5) / width
    elev = (0.5 - v) * math.pi  # [rad]
    sky = 0.25 + 0.35 * np.clip(np.sin(elev), 0, 1) ** 0.5
    ground = 0.06 + 0.04 * np.clip(-np.sin(elev), 0, 1)
    base = np.where(elev > 0, sky, ground)[:, None] * np.ones((1, width))
    img = np.stack([base * 0.9, base * 0.95, base * 1.05], axis=-1)
    for u0, u1, v0, v1, level in ((0.58, 0.70, 0.22, 0.36, 6.0), (0.80, 0.86, 0.30, 0.42, 3.0)):
        box = ((u >= u0) & (u <= u1))[None, :] & ((v >= v0) & (v <= v1))[:, None]
        img[box] = level
    return img.astype(np.float32)


def environment(scale: float = 1.0, width: int = 256) -> dict:
    """The procedural sky as a Mitsuba ``envmap`` emitter dict (needs a variant set)."""
    import mitsuba as mi

    return {"type": "envmap", "bitmap": mi.Bitmap(environment_image(width)), "scale": float(scale)}


def sphere_row(
    bsdfs: list[dict],
    *,
    width: int = 640,
    height: int | None = None,
    spp: int = 64,
    spacing: float = 2.4,
    fov_deg: float = 28.0,
    light_irradiance: float = 3.0,
    env_scale: float = 1.0,
    env_width: int = 256,
    max_depth: int = 4,
    sampler: str = "independent",
    emitter: str = "sky+sun",
) -> dict:
    """A scene dict with one unit sphere per BSDF dict, left to right along x.

    The camera looks down −z from a little above; ``height`` defaults to what fits the row.
    ``sampler``: a Mitsuba sampler plugin name (``"independent"``, ``"multijitter"``, ...).
    ``emitter``: ``"sky+sun"`` (the procedural sky and a directional light, default), ``"sky"``,
    ``"sun"`` or ``"constant"`` (a uniform white environment of radiance ``env_scale``).
    """
    if not bsdfs:
        raise ValueError("bsdfs must hold at least one BSDF dict")
    if emitter not in EMITTERS:
        raise ValueError(f"emitter must be one of {list(EMITTERS)}, got {emitter!r}")
    import mitsuba as mi

    n = len(bsdfs)
    span = (n - 1) * spacing + 2.6
    dist = 0.5 * span / math.tan(math.radians(fov_deg) / 2)
    if height is None:
        height = max(8, int(round(width * 3.0 / span)) // 2 * 2)
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(max_depth)},
        "sensor": {
            "type": "perspective",
            "fov": float(fov_deg),
            "fov_axis": "x",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=[0, 0.35 * dist / 4, dist], target=[0, 0, 0], up=[0, 1, 0]
            ),
            "film": {
                "type": "hdrfilm",
                "width": int(width),
                "height": int(height),
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": sampler, "sample_count": int(spp)},
        },
    }
    if emitter in ("sky+sun", "sky"):
        scene["sky"] = environment(env_scale, env_width)
    if emitter == "constant":
        scene["sky"] = {"type": "constant", "radiance": {"type": "rgb", "value": float(env_scale)}}
    if emitter in ("sky+sun", "sun"):
        scene["sun"] = {
            "type": "directional",
            "direction": [0.55, -0.6, -0.58],
            "irradiance": {"type": "rgb", "value": float(light_irradiance)},
        }
    x0 = -0.5 * (n - 1) * spacing
    for k, bsdf in enumerate(bsdfs):
        scene[f"sphere_{k}"] = {
            "type": "sphere",
            "center": [x0 + k * spacing, 0.0, 0.0],
            "radius": 1.0,
            "bsdf": bsdf,
        }
    return scene


def render(scene: dict, *, seed: int = 0, spp: int | None = None) -> np.ndarray:
    """Render a scene dict with the current variant: linear RGB ``(H, W, 3)`` float array."""
    import drjit as dr
    import mitsuba as mi

    sc = mi.load_dict(scene)
    img = mi.render(sc, seed=int(seed), spp=0 if spp is None else int(spp))
    dr.eval(img)
    return np.array(img, dtype=np.float64)[..., :3]


def to_srgb(img: np.ndarray, exposure: float = 1.0, *, white: float | None = None) -> np.ndarray:
    """Linear RGB → 8-bit sRGB (IEC 61966-2-1 transfer curve), clipped. With ``white``, the
    luminance is first compressed by the extended Reinhard curve ``L (1 + L/w²)/(1 + L)`` so
    that highlights up to ``w`` keep their shape (Reinhard et al. 2002, eq. 4)."""
    x = np.asarray(img, dtype=float) * exposure
    if white is not None:
        lum = np.maximum(x @ np.array([0.2126, 0.7152, 0.0722]), 1e-12)[..., None]
        x = x * ((1 + lum / white**2) / (1 + lum))
    x = np.clip(x, 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)
    return np.round(srgb * 255).astype(np.uint8)


def save_png(path, img: np.ndarray, *, exposure: float = 1.0) -> Path:
    """Write a linear-RGB image as an 8-bit sRGB PNG, atomically."""
    import matplotlib.image

    with atomic_path(path, suffix=".png") as tmp:
        matplotlib.image.imsave(tmp, to_srgb(img, exposure), format="png")
    return Path(path)


def block_mean(img: np.ndarray, block: int) -> np.ndarray:
    """Means over ``block × block`` pixel blocks (trailing partial blocks dropped)."""
    h, w = (img.shape[0] // block) * block, (img.shape[1] // block) * block
    x = img[:h, :w].reshape(h // block, block, w // block, block, *img.shape[2:])
    return x.mean(axis=(1, 3))


def image_difference(a: np.ndarray, b: np.ndarray, *, block: int = 8) -> float:
    """Mean absolute difference of block means over the mean of ``b``'s block means [-]
    (block averaging removes most of the Monte Carlo noise, not the bias)."""
    ba, bb = block_mean(a, block), block_mean(b, block)
    return float(np.abs(ba - bb).mean() / bb.mean())


def save_rows(
    path,
    rows: list[tuple[np.ndarray, str, list[str]]],
    *,
    exposure: float = 1.5,
    white: float | None = 24.0,
) -> Path:
    """A figure of rendered rows, each ``(linear RGB image, title, labels under the spheres)``,
    tone-mapped (:func:`to_srgb`), written atomically as PNG (matplotlib)."""
    import matplotlib.pyplot as plt

    from ..io import save_figure

    width = rows[0][0].shape[1]
    fig_w = max(6.0, width / 110)
    heights = [img.shape[0] / img.shape[1] * fig_w + 0.55 for img, _, _ in rows]
    fig, axes = plt.subplots(len(rows), 1, figsize=(fig_w, sum(heights)), squeeze=False)
    for ax, (img, title, labels) in zip(axes[:, 0], rows, strict=True):
        ax.imshow(to_srgb(img, exposure, white=white), interpolation="nearest")
        ax.set_title(title, fontsize=9)
        n = len(labels)  # sphere centres of sphere_row's default spacing (2.4) and margin (1.3)
        span = 2.4 * (n - 1) + 2.6
        ax.set_xticks([(1.3 + 2.4 * k) / span * img.shape[1] for k in range(n)], labels, fontsize=8)
        ax.set_yticks([])
        for side in ax.spines.values():
            side.set_visible(False)
    fig.tight_layout()
    return save_figure(fig, path)
