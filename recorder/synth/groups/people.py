"""Walking people made of textured boxes (legs and arms swing), drawn by a painter's algorithm.

A person stands at a ground point with a heading; torso, head, two legs (pivoting at the hip) and
two arms (at the shoulder, opposite phase) are oriented boxes whose visible faces are warped from
the person's own textures (``cv2.warpPerspective`` into the face's bounding box only), shaded by
the face normal. Faces of everything in view are drawn far to near; an id image records which
person each pixel shows (visibility of the ground truth).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from trackreplay.recorder.synth.texture import natural_texture

LIGHT = np.array([-0.4, -0.3, 0.87])  # from above, slightly left and behind the rig
_TEX = 48


def box_faces(lo: np.ndarray, hi: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Faces ``(corners (4, 3), outward normal (3,))`` of an axis-aligned box."""
    c = 0.5 * (np.asarray(lo) + np.asarray(hi))
    return oriented_box_faces(c, np.eye(3), 0.5 * (np.asarray(hi) - np.asarray(lo)))


def oriented_box_faces(centre: np.ndarray, axes: np.ndarray, half: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Faces of a box with columns of ``axes`` as its unit axes and ``half`` its half-sizes."""
    faces = []
    for k in range(3):
        i, j = [a for a in range(3) if a != k]
        for s in (-1.0, 1.0):
            n = axes[:, k] * s
            fc = centre + n * half[k]
            a, b = axes[:, i] * half[i], axes[:, j] * half[j]
            corners = np.stack([fc - a - b, fc + a - b, fc + a + b, fc - a + b])
            faces.append((corners, n))
    return faces


class Painter:
    """Draws textured faces into one view's image (and an optional id image), far to near."""

    def __init__(self, rig, right: bool, image: np.ndarray, ids: np.ndarray | None = None) -> None:
        self.rig, self.right, self.image, self.ids = rig, right, image, ids
        self.eye = rig.centre + (rig.R.T @ np.array([rig.baseline, 0.0, 0.0]) if right else 0.0)

    def draw_faces(self, faces, textures, ids, sort: bool = True) -> None:
        items = []
        for k, (corners, normal) in enumerate(faces):
            centre = corners.mean(axis=0)
            to_eye = self.eye - centre
            if float(normal @ to_eye) <= 0:
                continue  # back face
            items.append((float(np.linalg.norm(to_eye)), k))
        if sort:
            items.sort(key=lambda item: (-item[0], item[1]))
        h, w = self.image.shape[:2]
        for _, k in items:
            corners, normal = faces[k]
            cam = self.rig.to_camera(corners)
            if (cam[:, 2] < 0.2).any():
                continue
            uv = self.rig.project(cam, self.right)
            x0, y0 = np.floor(uv.min(axis=0)).astype(int)
            x1, y1 = np.ceil(uv.max(axis=0)).astype(int) + 1
            x0c, y0c, x1c, y1c = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
            if x1c <= x0c or y1c <= y0c:
                continue
            tex = textures[k]
            th, tw = tex.shape[:2]
            src = np.array([[0, 0], [tw - 1, 0], [tw - 1, th - 1], [0, th - 1]], np.float32)
            dst = (uv - [x0c, y0c]).astype(np.float32)
            H = cv2.getPerspectiveTransform(src, dst)
            size = (x1c - x0c, y1c - y0c)
            shade = 0.55 + 0.45 * max(0.0, float(normal @ LIGHT))
            warped = cv2.warpPerspective(tex, H, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            mask = np.zeros((size[1], size[0]), np.uint8)
            cv2.fillConvexPoly(mask, np.round(dst * 16).astype(np.int32), 1, cv2.LINE_8, 4)
            m = mask.astype(bool)
            region = self.image[y0c:y1c, x0c:x1c]
            region[m] = np.clip(warped[m].astype(np.float32) * shade, 0, 255).astype(np.uint8)
            if self.ids is not None and ids is not None:
                self.ids[y0c:y1c, x0c:x1c][m] = ids[k]


@dataclass(frozen=True)
class Look:
    """One person's textures: shirt, trousers, skin/hair (BGR uint8, _TEX x _TEX)."""

    shirt: np.ndarray
    trousers: np.ndarray
    head: np.ndarray

    @classmethod
    def make(cls, seed: int) -> Look:
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(0x9E0,)))

        def tex(colour, key, contrast):
            grey = natural_texture(_TEX, _TEX, seed * 31 + key, beta=1.2, lo=0, hi=255).astype(np.float32) / 255.0
            stripes = 0.5 + 0.5 * np.sin(np.arange(_TEX)[:, None] / rng.uniform(2.0, 5.0) + rng.uniform(0, 6.28))
            pattern = (1.0 - contrast) + contrast * (0.6 * grey + 0.4 * stripes)
            return np.clip(pattern[..., None] * np.asarray(colour, np.float32)[None, None, :], 0, 255).astype(np.uint8)

        shirt = rng.uniform(60, 250, 3)
        trousers = rng.uniform(30, 160, 3)
        return cls(tex(shirt, 1, 0.6), tex(trousers, 2, 0.5), tex((90, 130, 190), 3, 0.4))


# body parts: (name, centre offset in the body frame (x right, y forward, z up), size, pivot z or None, swing sign)
PARTS = (
    ("leg_l", (-0.1, 0.0, 0.44), (0.15, 0.17, 0.88), 0.88, 1.0),
    ("leg_r", (0.1, 0.0, 0.44), (0.15, 0.17, 0.88), 0.88, -1.0),
    ("torso", (0.0, 0.0, 1.19), (0.42, 0.24, 0.62), None, 0.0),
    ("head", (0.0, 0.0, 1.64), (0.2, 0.22, 0.26), None, 0.0),
    ("arm_l", (-0.28, 0.0, 1.16), (0.1, 0.11, 0.6), 1.46, -1.0),
    ("arm_r", (0.28, 0.0, 1.16), (0.1, 0.11, 0.6), 1.46, 1.0),
)
TORSO_Z = 1.19
HEIGHT = 1.77


def person_faces(ground: np.ndarray, heading: float, phase: float, look: Look, swing_deg: float = 25.0):
    """Faces and their textures of one person standing at ``ground`` (world, Z of the ground under
    them) facing ``heading`` (radians from +X), walking ``phase`` (radians) into the stride."""
    ch, sh = np.cos(heading), np.sin(heading)
    fwd, right, up = np.array([ch, sh, 0.0]), np.array([sh, -ch, 0.0]), np.array([0.0, 0.0, 1.0])
    body = np.stack([right, fwd, up], axis=1)  # body frame -> world
    faces, textures = [], []
    for name, offset, size, pivot, sign in PARTS:
        centre = np.asarray(offset, np.float64)
        axes = np.eye(3)
        if pivot is not None:
            a = np.deg2rad(swing_deg) * sign * np.sin(phase)
            rot = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])  # about body x
            p = np.array([centre[0], 0.0, pivot])
            centre = p + rot @ (centre - p)
            axes = rot
        world_centre = ground + body @ centre
        tex = look.trousers if name.startswith("leg") else look.head if name == "head" else look.shirt
        for face in oriented_box_faces(world_centre, body @ axes, 0.5 * np.asarray(size)):
            faces.append(face)
            textures.append(tex)
    return faces, textures


def person_corners(ground: np.ndarray, heading: float, phase: float) -> np.ndarray:
    """Every body-box corner (world), for the person's image box."""
    faces, _ = person_faces(ground, heading, phase, _NO_LOOK)
    return np.concatenate([c for c, _ in faces])


_NO_LOOK = Look(np.zeros((2, 2, 3), np.uint8), np.zeros((2, 2, 3), np.uint8), np.zeros((2, 2, 3), np.uint8))
