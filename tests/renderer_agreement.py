"""How far two pictures of one scene agree: the ray caster's and cell projection's (issue 32).

Pictures are ``(H, W, 3)`` uint8 with their ``(H, W)`` window depth. A pixel shows the
surface (or a mesh) where it differs from the background; silhouette pixels (a 3x3
neighbourhood mixed in either picture's mask) are left out, as the issue's acceptance says.
"""

from dataclasses import dataclass

import numpy as np

#: the acceptance of issue 32: masks equal on this share of non-silhouette pixels ...
MASK_SHARE = 0.995
#: ... colours within this many 8-bit steps where both show something ...
COLOUR_STEPS = 2
#: ... on this share of those pixels (a few grazing pixels of a fold differ more)
COLOUR_SHARE = 0.995
#: window depths agree within this (the ray caster's frames reach the window in 24 bits)
DEPTH_TOLERANCE = 1e-5


@dataclass
class Agreement:
    mask_share: float  # of non-silhouette pixels whose masks agree
    both: int  # non-silhouette pixels both pictures draw
    colour_max: int  # largest colour difference there (8-bit steps)
    colour_share: float  # share of them within COLOUR_STEPS
    depth_max: float  # largest window-depth difference there
    depth_share: float  # share of them within DEPTH_TOLERANCE

    def __str__(self) -> str:
        return (f"mask {100 * self.mask_share:.3f} %, {self.both} px both, colour max "
                f"{self.colour_max}/255 ({100 * self.colour_share:.3f} % within "
                f"{COLOUR_STEPS}), depth max {self.depth_max:.2e} "
                f"({100 * self.depth_share:.3f} % within {DEPTH_TOLERANCE:g})")

    def acceptable(self) -> bool:
        return (self.mask_share >= MASK_SHARE and self.colour_share >= COLOUR_SHARE
                and self.depth_share >= COLOUR_SHARE)


def _mixed(mask: np.ndarray) -> np.ndarray:
    """Pixels whose 3x3 neighbourhood holds both values of ``mask``."""
    p = np.pad(mask, 1, mode="edge")
    h, w = mask.shape
    win = np.stack([p[i:i + h, j:j + w] for i in range(3) for j in range(3)])
    return win.any(axis=0) & ~win.all(axis=0)


def agreement(a, b, background) -> Agreement:
    """Figures of pictures ``a = (colour, depth)`` and ``b`` over the ``background``."""
    (ca, da), (cb, db) = a, b
    bg = np.asarray(background, dtype=np.uint8)[:3]
    ha = np.any(ca[..., :3] != bg, axis=-1)
    hb = np.any(cb[..., :3] != bg, axis=-1)
    inner = ~(_mixed(ha) | _mixed(hb))
    both = ha & hb & inner
    dcol = np.abs(ca[both][:, :3].astype(int) - cb[both][:, :3].astype(int)).max(axis=1)
    ddepth = np.abs(da[both].astype(np.float64) - db[both].astype(np.float64))
    return Agreement(float(np.mean(ha[inner] == hb[inner])), int(both.sum()),
                     int(dcol.max(initial=0)), float(np.mean(dcol <= COLOUR_STEPS)),
                     float(ddepth.max(initial=0.0)),
                     float(np.mean(ddepth <= DEPTH_TOLERANCE)) if len(ddepth) else 1.0)


def scene_picture(scene, size, device=None):
    """``(colour, depth)`` of ``scene`` as :func:`splineviz.render.scene_view.render_scene`
    draws it, and the depth buffer of that render, in a window without multisampling (as
    the GUI's view; render_scene draws a surface by cell projection so too, and the edges
    of meshes must not differ by the window's antialiasing)."""
    from splineviz.render.scene_view import OffscreenRenderer
    from splineviz.render.volume_rendering import window_depth

    with OffscreenRenderer(scene, size, device=device) as r:
        (pl, _view), = r._views
        pl.render_window.SetMultiSamples(0)
        colour = r.render()
        return colour, window_depth(pl, *size)
