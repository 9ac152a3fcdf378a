"""Broadcast-camera frames of the tee shot, rendered from the world model for a given camera pose.

Per pixel the line of sight is ``R [(u - cx)/fx, (v - cy)/fy, 1]``. The head never rolls, so the
vertical component of a ray depends on the row only: rows above the horizon are sky, rows below are
ground. Sky: a gradient in elevation and clouds on a plane 1.5 km up (a periodic 1/f texture
looked up where the ray meets the plane, so clouds stay put as the camera pans). Ground: the ray
meets Z = 0; grass texture (mip-mapped by the pixel's footprint), fairway, green, tee box, bunker
and mowing stripes are functions of the ground point, then distance haze. A tree line stands on
a circle around the tee. Spheres (ball, distractors, a bird) are anti-aliased discs of apparent
radius ``f r / range``, averaged over sub-samples of the shutter interval (motion blur) and shaded
by the sun. An occluder (the occlusion variant: a tree or a passer-by) is drawn from its analytic coverage.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np

from trackreplay.recorder.synth.golf.world import Blob, World
from trackreplay.recorder.synth.texture import natural_texture
from trackreplay.trackers.geometry.ptz import PtzCamera

# Colours, BGR 0..255.
ZENITH = np.array([200.0, 135.0, 70.0], np.float32)
HORIZON = np.array([232.0, 214.0, 196.0], np.float32)
CLOUD = np.array([236.0, 236.0, 234.0], np.float32)
CLOUD_SHADE = np.array([196.0, 194.0, 192.0], np.float32)
HAZE = np.array([215.0, 205.0, 190.0], np.float32)
ROUGH = np.array([42.0, 98.0, 58.0], np.float32)
FAIRWAY = np.array([56.0, 138.0, 82.0], np.float32)
GREEN = np.array([62.0, 150.0, 90.0], np.float32)
TEEBOX = np.array([58.0, 142.0, 86.0], np.float32)
SAND = np.array([168.0, 200.0, 220.0], np.float32)
TREES = np.array([38.0, 68.0, 42.0], np.float32)
BALL = np.array([246.0, 248.0, 250.0], np.float32)

GRASS_TEXEL = 0.015  # m per texel of the fine grass texture (512 texels -> 7.7 m tile)
PATCH_TEXEL = 2.0  # m per texel of the large-scale patches (256 -> 512 m)
CLOUD_TEXEL = 8.0  # m per texel on the cloud plane (512 -> 4 km)
HAZE_DISTANCE = 2500.0  # m


@dataclass(frozen=True)
class FrameView:
    """What one frame sees: the pose at capture time and sub-samples over the shutter interval."""

    index: int
    camera_time: float  # log-clock seconds of the capture
    camera: PtzCamera  # pose at the frame's capture time
    sub_times: np.ndarray  # (K,) log-clock seconds within the exposure
    sub_cameras: tuple[PtzCamera, ...]  # pose at each sub time
    ball: np.ndarray  # (K, 3) ball centre at each sub time

    @cached_property
    def _stack(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        Rs = np.stack([c.R for c in self.sub_cameras])  # (K, 3, 3) world-from-camera
        k = np.array([[c.intrinsics.fx, c.intrinsics.fy, c.intrinsics.cx, c.intrinsics.cy] for c in self.sub_cameras])
        pos = np.stack([c.position for c in self.sub_cameras])
        return Rs, k, pos

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Image points (K, 2), ranges (K,) and fx (K,) of one world point per sub-sample (NaN behind)."""
        Rs, k, pos = self._stack
        rel = points - pos
        cam = np.einsum("kji,kj->ki", Rs, rel)  # R^T rel
        with np.errstate(divide="ignore", invalid="ignore"):
            u = k[:, 0] * cam[:, 0] / cam[:, 2] + k[:, 2]
            v = k[:, 1] * cam[:, 1] / cam[:, 2] + k[:, 3]
        ahead = cam[:, 2] > 1e-9
        uv = np.stack([np.where(ahead, u, np.nan), np.where(ahead, v, np.nan)], axis=1)
        return uv, np.linalg.norm(rel, axis=1), k[:, 0]


def _smooth(x: np.ndarray, width: np.ndarray | float) -> np.ndarray:
    """Anti-aliased step: 0 below -width/2, 1 above +width/2 (``x`` a signed distance)."""
    return np.clip(x / np.maximum(width, 1e-4) + 0.5, 0.0, 1.0)


def _wrap(x: np.ndarray, texel: float, n: int) -> np.ndarray:
    """Texture coordinate of ``x`` metres in a periodic texture of ``n`` texels (np.mod is ~50x slower)."""
    t = x * (1.0 / (texel * n))
    t -= np.floor(t)
    t *= n
    return t


def _lerp_channels(base: np.ndarray, layers: list[tuple[np.ndarray, np.ndarray]], gain: np.ndarray) -> list[np.ndarray]:
    """Per channel: start from colour ``base``, blend each (mask, colour) over it, multiply by ``gain``."""
    out = []
    for ch in range(3):
        acc = np.full(gain.shape, float(base[ch]), np.float32)
        for mask, colour in layers:
            acc += mask * (float(colour[ch]) - acc)
        acc *= gain
        out.append(acc)
    return out


def _signed(tex: np.ndarray) -> np.ndarray:
    return (tex.astype(np.float32) / 127.5 - 1.0).astype(np.float32)


class GolfRenderer:
    """Renders frames of one world at one image size; textures are built once from ``seed``."""

    def __init__(self, world: World, width: int, height: int, seed: int, *, ball_radius: float) -> None:
        self.world = world
        self.width, self.height = int(width), int(height)
        self.ball_radius = float(ball_radius)
        ss = np.random.SeedSequence(seed, spawn_key=(0x601F,))
        tex_seeds = [int(s.generate_state(1)[0]) for s in ss.spawn(4)]
        grass = _signed(natural_texture(512, 512, tex_seeds[0], beta=1.4, lo=0, hi=255))
        self.grass = [grass]
        while self.grass[-1].shape[0] > 8:  # a periodic mip pyramid: reduce a 3x3 tiling, keep the middle
            t = self.grass[-1]
            n = t.shape[0] // 2
            self.grass.append(np.ascontiguousarray(cv2.pyrDown(np.tile(t, (3, 3)))[n:2 * n, n:2 * n]))
        self.patches = _signed(natural_texture(256, 256, tex_seeds[1], beta=2.4, lo=0, hi=255))
        clouds = natural_texture(512, 512, tex_seeds[2], beta=2.6, lo=0, hi=255).astype(np.float32) / 255.0
        self.clouds = clouds
        noise_rng = np.random.default_rng(tex_seeds[3])
        pad = 32
        self._noise = np.clip(noise_rng.normal(0.0, 1.6, (self.height + pad, self.width + pad, 3)), -6, 6).astype(np.float32)
        self._noise_rng_seed = tex_seeds[3]
        self._cols = np.arange(self.width, dtype=np.float32)
        self._rows = np.arange(self.height, dtype=np.float32)
        self._lw, self._lh = (self.width + 1) // 2, (self.height + 1) // 2
        self._lo_cols = ((np.arange(self._lw) + 0.5) * (self.width / self._lw) - 0.5).astype(np.float32)
        self._lo_rows = ((np.arange(self._lh) + 0.5) * (self.height / self._lh) - 0.5).astype(np.float32)

    # ---------------------------------------------------------------- background
    #
    # The smooth parts (sky, clouds, course regions, stripes, patches, haze, tree line) are computed
    # on a half-resolution grid and upsampled; only the fine grass texture is sampled per pixel.
    # Low-res sample i sits at full-res coordinate (i + 0.5) * full / low - 0.5, which is where
    # cv2.resize(INTER_LINEAR) puts it, so the two layers line up exactly.

    def _rays_at(self, cam: PtzCamera, cols: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Unnormalised world rays (X, Y per pixel; Z per row: the head never rolls) and their norms."""
        k = cam.intrinsics
        R = cam.R.tolist()  # Python floats: float32 arrays stay float32
        xu = (cols - float(k.cx)) * (1.0 / float(k.fx))
        yv = (rows - float(k.cy)) * (1.0 / float(k.fy))
        dX = (R[0][0] * xu)[None, :] + (R[0][1] * yv + R[0][2])[:, None]
        dY = (R[1][0] * xu)[None, :] + (R[1][1] * yv + R[1][2])[:, None]
        dZ = R[2][1] * yv + R[2][2]  # R[2][0] == 0: one vertical component per row
        norm = np.sqrt((xu * xu)[None, :] + (yv * yv + 1.0)[:, None])
        return dX, dY, dZ, norm

    def background(self, cam: PtzCamera) -> np.ndarray:
        """Sky, ground and tree line under pose ``cam`` as float32 BGR."""
        c = tuple(float(v) for v in cam.position)
        low = np.zeros((self._lh, self._lw, 4), np.float32)  # BGR + relative grass-texture amplitude
        dX, dY, dZ, norm = self._rays_at(cam, self._lo_cols, self._lo_rows)
        n_sky = int(np.count_nonzero(dZ > 1e-6))  # dZ decreases down the image
        if n_sky > 0:
            low[:n_sky, :, :3] = self._sky(c, dX[:n_sky], dY[:n_sky], dZ[:n_sky], norm[:n_sky])
        if n_sky < self._lh:
            low[n_sky:] = self._ground(cam, c, dX[n_sky:], dY[n_sky:], dZ[n_sky:], norm[n_sky:])
        self._treeline(low, cam, c, dX, dY, dZ, norm)
        up = cv2.resize(low, (self.width, self.height), interpolation=cv2.INTER_LINEAR)
        img = np.ascontiguousarray(up[..., :3])
        self._detail(img, up[..., 3], cam, c)
        return img

    def _sky(self, c, dX, dY, dZ, norm) -> np.ndarray:
        sin_el = dZ[:, None] / norm
        g = 1.0 - np.exp(-4.0 * sin_el)
        s = ((self.world.cloud_height - c[2]) / dZ)[:, None]
        n = self.clouds.shape[0]
        tex = cv2.remap(self.clouds, _wrap(c[0] + dX * s, CLOUD_TEXEL, n), _wrap(c[1] + dY * s, CLOUD_TEXEL, n),
                        cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)
        dens = np.clip((tex - 0.52) * (1.0 / 0.22), 0.0, 1.0)
        dens *= np.clip((sin_el - 0.03) * (1.0 / 0.12), 0.0, 1.0)
        shade = np.clip((tex - 0.52) * (1.0 / 0.4), 0.0, 1.0)
        out = []
        for ch in range(3):
            sky = float(HORIZON[ch]) + g * float(ZENITH[ch] - HORIZON[ch])
            cloud = float(CLOUD[ch]) + shade * float(CLOUD_SHADE[ch] - CLOUD[ch])
            sky += dens * (cloud - sky)
            out.append(sky)
        return np.dstack(out)

    def _ground(self, cam: PtzCamera, c, dX, dY, dZ, norm) -> np.ndarray:
        """Course colour (with haze) and the fine-texture amplitude, on low-res ground rows."""
        course = self.world.course
        fx = float(cam.intrinsics.fx)
        dz = np.minimum(dZ, -1e-6)
        s = (-c[2] / dz)[:, None]
        X = c[0] + dX * s
        Y = c[1] + dY * s
        dist = s * norm
        sin_inc = np.maximum(-dz[:, None] / norm, 0.01)
        fp = dist * (1.0 / fx) / np.sqrt(sin_inc)  # footprint of a full-res pixel on the ground, m
        along, across = course.to_local(X, Y)
        across_c = across - float(course.fairway_bend) * (along * 0.01) ** 2
        aa = fp * 2.0  # the low-res grid is two pixels apart
        fairway = _smooth(float(course.fairway_half_width) - np.abs(across_c), aa) * _smooth(along - 30.0, aa)
        g0, g1 = (float(v) for v in course.green_centre)
        ra, rb = (float(v) for v in course.green_radii)
        q = np.sqrt(((along - g0) * (1.0 / ra)) ** 2 + ((across - g1) * (1.0 / rb)) ** 2)
        green = _smooth((1.0 - q) * min(ra, rb), aa)
        b0, b1 = (float(v) for v in course.bunker_centre)
        ba, bb = (float(v) for v in course.bunker_radii)
        qb = np.sqrt(((along - b0) * (1.0 / ba)) ** 2 + ((across - b1) * (1.0 / bb)) ** 2)
        bunker = _smooth((1.0 - qb) * min(ba, bb), aa)
        t0, t1, tw = (float(v) for v in course.teebox)
        teebox = _smooth(np.minimum(np.minimum(along - t0, t1 - along), tw - np.abs(across)), aa)
        n = self.patches.shape[0]
        patch = cv2.remap(self.patches, _wrap(X, PATCH_TEXEL, n), _wrap(Y, PATCH_TEXEL, n), cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_WRAP)
        sw = float(course.stripe_width)
        stripe = np.clip(np.sin(along * (np.pi / sw)) * (sw / np.pi) / np.maximum(aa, 1e-3), -1.0, 1.0)
        stripe *= np.clip(1.0 - aa * (2.0 / sw), 0.0, 1.0)
        mown = np.maximum(np.maximum(fairway, green), teebox)
        amp = 0.30 - 0.16 * mown - 0.06 * green
        amp += bunker * (0.05 - amp)
        bright = 1.0 + (1.0 - bunker) * (0.10 * patch + 0.07 * stripe * mown)
        haze = 1.0 - np.exp(dist * (-1.0 / HAZE_DISTANCE))
        lit = bright * (1.0 - haze)
        chans = _lerp_channels(ROUGH, [(fairway, FAIRWAY), (teebox, TEEBOX), (green, GREEN), (bunker, SAND)], lit)
        for ch in range(3):
            chans[ch] += haze * float(HAZE[ch])
        # Relative amplitude of the fine texture in the final colour: base*lit*(1 + amp/bright*fine) + haze.
        rel = amp * lit / (lit + haze * (float(HAZE.mean()) / float(FAIRWAY.mean())))
        return np.dstack([*chans, rel / bright])

    def _detail(self, img: np.ndarray, rel: np.ndarray, cam: PtzCamera, c) -> None:
        """Multiply the ground by fine grass sampled per pixel at the mip level of its footprint."""
        dZ = self._rays_at(cam, self._cols[:1], self._rows)[2]
        r0 = int(np.count_nonzero(dZ > 1e-6))
        if r0 >= self.height:
            return
        dX, dY, dZ, norm = self._rays_at(cam, self._cols, self._rows[r0:])
        dz = np.minimum(dZ, -1e-6)
        s = (-c[2] / dz)[:, None]
        X = c[0] + dX * s
        Y = c[1] + dY * s
        # Level of detail per row, from the footprint at the image centre column.
        k = cam.intrinsics
        xc = (self._cols[self.width // 2] - float(k.cx)) / float(k.fx)
        nrm = np.sqrt(xc * xc + ((self._rows[r0:] - float(k.cy)) / float(k.fy)) ** 2 + 1.0)
        dist = (-c[2] / dz) * nrm
        fp = dist / float(k.fx) / np.sqrt(np.maximum(-dz / nrm, 0.01))
        top = len(self.grass) - 1
        level = np.clip(np.log2(np.maximum(fp, 1e-6) / GRASS_TEXEL), 0.0, float(top))
        fine = np.zeros_like(X)
        for lv in range(top + 1):
            wgt = np.clip(1.0 - np.abs(level - lv), 0.0, 1.0)
            rows = np.nonzero(wgt > 0.0)[0]
            if len(rows) == 0:
                continue
            a, b = int(rows[0]), int(rows[-1]) + 1
            tex = self.grass[lv]
            n = tex.shape[0]
            texel = GRASS_TEXEL * 2**lv
            sample = cv2.remap(tex, _wrap(X[a:b], texel, n), _wrap(Y[a:b], texel, n), cv2.INTER_LINEAR,
                               borderMode=cv2.BORDER_WRAP)
            fine[a:b] += wgt[a:b, None] * sample
        gain = 1.0 + rel[r0:] * fine
        img[r0:] *= gain[..., None]

    def _treeline(self, low: np.ndarray, cam: PtzCamera, c, dX, dY, dZ, norm) -> None:
        """Distant trees standing on a circle around the tee (drawn into the low-res layer)."""
        course = self.world.course
        rt = float(course.treeline_radius)
        hmax = float(course.treeline_height[1])
        ch = (c[0] - float(course.tee[0]), c[1] - float(course.tee[1]))
        cr = math.hypot(*ch)
        dh = np.sqrt(dX * dX + dY * dY)
        slope = dZ[:, None] / np.maximum(dh, 1e-6)
        lo_s, hi_s = (0.0 - c[2]) / (rt + cr) - 0.01, (hmax - c[2]) / (rt - cr) + 0.01
        rows = np.nonzero(((slope >= lo_s) & (slope <= hi_s)).any(axis=1))[0]
        if len(rows) == 0:
            return
        r0, r1 = int(rows[0]), int(rows[-1]) + 1
        ax, ay = dX[r0:r1], dY[r0:r1]
        a = ax * ax + ay * ay
        b = 2.0 * (ch[0] * ax + ch[1] * ay)
        cc = cr * cr - rt * rt
        s = (-b + np.sqrt(b * b - 4.0 * a * cc)) / (2.0 * a)
        z = c[2] + s * dZ[r0:r1, None]
        az = np.arctan2(ch[1] + s * ay, ch[0] + s * ax)
        height = course.treeline_profile(az)
        dist = s * norm[r0:r1]
        pix = dist * (2.0 / float(cam.intrinsics.fy))  # low-res pixels are two full-res pixels
        cov = _smooth(height - z, pix) * _smooth(z, pix)
        if not cov.any():
            return
        n = self.patches.shape[0]
        leaf = cv2.remap(self.patches, _wrap(az * rt, 0.4, n), _wrap(z, 0.4, n), cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_WRAP)
        haze = 1.0 - np.exp(dist * (-1.0 / HAZE_DISTANCE))
        gain = (1.0 + 0.6 * leaf + (0.25 / hmax) * z - 0.1) * (1.0 - haze)
        block = low[r0:r1]
        for ch in range(3):
            tree = float(TREES[ch]) * gain + haze * float(HAZE[ch])
            plane = block[..., ch]
            plane += cov * (tree - plane)
        block[..., 3] *= 1.0 - cov

    # ---------------------------------------------------------------- objects

    def _sphere(self, img: np.ndarray, view: FrameView, centres: np.ndarray, radius: float,
                colour: np.ndarray, aspect: float = 1.0, flap: np.ndarray | None = None) -> None:
        """Blend a motion-blurred, anti-aliased, sun-shaded disc into ``img`` (float BGR)."""
        uv, ranges, fx = view.project(centres)
        if not np.isfinite(uv).all():
            return
        cams = view.sub_cameras
        r = fx * radius / ranges  # px
        ext = r.max() * aspect + 2.0
        x0 = max(int(math.floor(uv[:, 0].min() - ext)), 0)
        x1 = min(int(math.ceil(uv[:, 0].max() + ext)) + 1, self.width)
        y0 = max(int(math.floor(uv[:, 1].min() - ext)), 0)
        y1 = min(int(math.ceil(uv[:, 1].max() + ext)) + 1, self.height)
        if x0 >= x1 or y0 >= y1:
            return
        px = np.arange(x0, x1, dtype=np.float64)[None, None, :]
        py = np.arange(y0, y1, dtype=np.float64)[None, :, None]
        dx = (px - uv[:, 0, None, None]) / aspect
        dy = py - uv[:, 1, None, None]
        rr = r[:, None, None]
        d = np.sqrt(dx * dx + dy * dy)
        cov = np.clip(rr + 0.5 - d, 0.0, 1.0)
        # Tiny discs: keep the covered area equal to the disc's true area (pi r^2 aspect).
        total = cov.sum(axis=(1, 2))
        area = math.pi * r * r * aspect
        scale = np.where(total > area, area / np.maximum(total, 1e-12), 1.0)
        cov *= scale[:, None, None]
        # Lambert shading of a sphere facing the camera, sun in camera coordinates.
        sun = cams[len(cams) // 2].R.T @ self.world.sun
        nx = np.clip(dx / np.maximum(rr, 1e-6), -1, 1)
        ny = np.clip(dy / np.maximum(rr, 1e-6), -1, 1)
        nz = -np.sqrt(np.clip(1.0 - nx * nx - ny * ny, 0.0, 1.0))
        shade = 0.74 + 0.26 * np.clip(nx * sun[0] + ny * sun[1] + nz * sun[2], 0.0, 1.0)
        if flap is not None:
            shade = shade * flap[:, None, None]
        k = len(cams)
        cover = (cov.sum(axis=0) / k).astype(np.float32)
        lum = ((cov * shade).sum(axis=0) / np.maximum(cov.sum(axis=0), 1e-9)).astype(np.float32)
        cover = np.minimum(cover, 1.0)[..., None]
        block = img[y0:y1, x0:x1]
        block += cover * (colour * lum[..., None] - block)

    def _blob(self, img: np.ndarray, view: FrameView, blob: Blob) -> None:
        pos = blob.at(view.sub_times)
        flap = None
        if blob.kind == "bird":
            flap = (0.85 + 0.15 * np.sin(2 * np.pi * 6.0 * view.sub_times)).astype(np.float64)
        self._sphere(img, view, pos, blob.radius, np.asarray(blob.colour, np.float32), blob.aspect, flap)

    def _occluder(self, img: np.ndarray, cam: PtzCamera, t: float) -> None:
        occ = self.world.occluder
        if occ is None:
            return
        k = cam.intrinsics
        pts, rad = occ.extent(t)
        dist = np.linalg.norm(pts - cam.position, axis=1)
        uv = cam.project_points(pts)
        ok = np.isfinite(uv[:, 0])
        if not ok.any():
            return
        ext = k.fx * rad[ok] / dist[ok] + 3
        x0 = max(int(np.floor((uv[ok, 0] - ext).min())), 0)
        x1 = min(int(np.ceil((uv[ok, 0] + ext).max())) + 1, self.width)
        y0 = max(int(np.floor((uv[ok, 1] - ext).min())), 0)
        y1 = min(int(np.ceil((uv[ok, 1] + ext).max())) + 1, self.height)
        if not ok.all():  # part of it behind the camera plane: be generous
            x0, x1, y0, y1 = 0, self.width, 0, self.height
        if x0 >= x1 or y0 >= y1:
            return
        bx, by, dz, nn = self._rays_at(cam, self._cols[x0:x1], self._rows[y0:y1])
        bz = np.broadcast_to(dz[:, None], bx.shape)
        flat = np.stack([bx / nn, by / nn, bz / nn], axis=-1).reshape(-1, 3).astype(np.float64)
        block = img[y0:y1, x0:x1]
        leaf = None
        for cov, colour, textured in occ.parts(cam.position, flat, 1.0 / float(k.fx), t):
            if not cov.any():
                continue
            cov = cov.reshape(bx.shape)
            gain = 1.0
            if textured:
                if leaf is None:
                    az = np.degrees(np.arctan2(flat[:, 1], flat[:, 0])).reshape(bx.shape).astype(np.float32)
                    el = np.degrees(np.arcsin(np.clip(flat[:, 2], -1, 1))).reshape(bx.shape).astype(np.float32)
                    tex = self.grass[2]
                    n = tex.shape[0]
                    leaf = cv2.remap(tex, _wrap(az, 1.0 / 90.0, n), _wrap(el, 1.0 / 90.0, n), cv2.INTER_LINEAR,
                                     borderMode=cv2.BORDER_WRAP)
                gain = 1.0 + 0.45 * leaf
            for ch in range(3):
                plane = block[..., ch]
                plane += cov * (float(colour[ch]) * gain - plane)

    # ---------------------------------------------------------------- frame

    def render(self, view: FrameView, *, draw_ball: bool = True, noise: bool = True) -> np.ndarray:
        """The frame as ``uint8`` BGR."""
        cam = view.camera
        img = self.background(cam)
        items: list[tuple[float, int, object]] = []
        for i, blob in enumerate(self.world.blobs):
            p = blob.at(view.sub_times[len(view.sub_times) // 2])[0]
            items.append((float(np.linalg.norm(p - cam.position)), i, blob))
        if draw_ball:
            mid = view.ball[len(view.ball) // 2]
            items.append((float(np.linalg.norm(mid - cam.position)), -1, "ball"))
        t = float(view.sub_times[len(view.sub_times) // 2])
        if self.world.occluder is not None:
            items.append((self.world.occluder.distance(cam.position, t), -2, "occluder"))
        for _, _, item in sorted(items, key=lambda it: (-it[0], it[1])):
            if item == "ball":
                self._sphere(img, view, view.ball, self.ball_radius, BALL)
            elif item == "occluder":
                self._occluder(img, cam, float(view.camera_time))
            else:
                self._blob(img, view, item)  # type: ignore[arg-type]
        if noise:
            rng = np.random.default_rng([self._noise_rng_seed, view.index])
            oy, ox = rng.integers(0, 32, 2)
            img += self._noise[oy:oy + self.height, ox:ox + self.width]
        return cv2.convertScaleAbs(img)  # rounds and saturates to uint8 (all values are >= 0)
