"""Rebuild the app icon ``resources/icons/splineviz.svg``.

A wavy height field z = h(x, y) inside its data box [-1, 1]^3, seen from above at an angle,
drawn as flat-shaded quads (Phong: ambient, diffuse, a little specular) back to front (the
painter's order along the view direction), over a rounded dark-blue square. The box's edges
that meet the hidden corner are drawn faintly behind the surface, the others in front.
The toolbar icons next to it are written by hand.

Usage::

    python resources/tools/make_app_icon.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parents[1] / "icons" / "splineviz.svg"
#: quads per side of the surface (finer: smoother, larger file)
N = 30
#: view direction (from the data to the eye): azimuth and elevation, degrees
AZIMUTH, ELEVATION = 28.0, 30.0
#: surface colour and light (world direction towards the light)
BASE = np.array([0.97, 0.72, 0.38])
LIGHT = np.array([0.2, -0.6, 1.0])

_az, _el = np.radians(AZIMUTH), np.radians(ELEVATION)
VIEW = np.array([np.cos(_el) * np.cos(_az), np.cos(_el) * np.sin(_az), np.sin(_el)])
RIGHT = np.cross([0.0, 0.0, 1.0], VIEW)
RIGHT /= np.linalg.norm(RIGHT)
UP = np.cross(VIEW, RIGHT)
CORNERS = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]


def _fit():
    c = np.array(CORNERS, float)
    sx, sy = c @ RIGHT, -(c @ UP)
    scale = 46.0 / max(np.ptp(sx), np.ptp(sy))  # the box spans 46 of the 64 units
    return scale, 32 - scale * (sx.max() + sx.min()) / 2, 32 - scale * (sy.max() + sy.min()) / 2


SCALE, CX, CY = _fit()


def screen(x, y, z) -> tuple[float, float]:
    """Icon coordinates (y down) of the world point (x, y, z)."""
    p = np.array([x, y, z], float)
    return CX + SCALE * (p @ RIGHT), CY - SCALE * (p @ UP)


def height(x, y):
    return 0.30 * np.sin(3.4 * x + 0.6) * np.cos(2.8 * y - 0.4) - 0.02


def _path(points, close=False) -> str:
    return "M" + "L".join(f"{x:.1f} {y:.1f}" for x, y in points) + ("z" if close else "")


def surface() -> list[str]:
    light = LIGHT / np.linalg.norm(LIGHT)
    half = (light + VIEW) / np.linalg.norm(light + VIEW)
    g = np.linspace(-1, 1, N + 1)
    quads = []
    for i in range(N):
        for j in range(N):
            xs = (g[i], g[i + 1], g[i + 1], g[i])
            ys = (g[j], g[j], g[j + 1], g[j + 1])
            xm, ym, e = (g[i] + g[i + 1]) / 2, (g[j] + g[j + 1]) / 2, 1e-4
            dx = (height(xm + e, ym) - height(xm - e, ym)) / (2 * e)
            dy = (height(xm, ym + e) - height(xm, ym - e)) / (2 * e)
            n = np.array([-dx, -dy, 1.0])
            n /= np.linalg.norm(n)
            rgb = np.clip(BASE * (0.28 + 0.72 * max(0.0, n @ light))
                          + 0.3 * max(0.0, n @ half) ** 40, 0, 1)
            col = "#" + "".join(f"{round(255 * v):02x}" for v in rgb)
            d = _path([screen(a, b, height(a, b)) for a, b in zip(xs, ys, strict=True)], True)
            quads.append((float(np.array([xm, ym, height(xm, ym)]) @ VIEW), d, col))
    quads.sort()  # far to near
    # the stroke in the fill colour closes the hairline seams between quads
    return [f'    <path d="{d}" fill="{c}" stroke="{c}"/>' for _, d, c in quads]


def main() -> None:
    hidden = min(CORNERS, key=lambda p: np.dot(p, VIEW))
    edges = [(a, b) for a in CORNERS for b in CORNERS
             if a < b and sum(p != q for p, q in zip(a, b, strict=True)) == 1]
    back = "".join(_path([screen(*a), screen(*b)]) for a, b in edges if hidden in (a, b))
    front = "".join(_path([screen(*a), screen(*b)]) for a, b in edges if hidden not in (a, b))
    t = np.linspace(-1, 1, 40)  # where the surface meets the two near walls
    rim = (_path([screen(1, v, height(1, v)) for v in t])
           + _path([screen(v, 1, height(v, 1)) for v in t]))
    quads = "\n".join(surface())
    svg = f'''<svg xmlns="http://www.w3.org/2000/svg" width="64" height="64" viewBox="0 0 64 64">
  <title>splineviz</title>
  <desc>A smooth wavy isosurface inside the box of its data (made by resources/tools/make_app_icon.py)</desc>
  <defs>
    <linearGradient id="bg" x1="0" y1="0" x2="0" y2="1">
      <stop offset="0" stop-color="#2e4270"/>
      <stop offset="1" stop-color="#161e35"/>
    </linearGradient>
  </defs>
  <rect x="3" y="3" width="58" height="58" rx="13" fill="url(#bg)"/>
  <path d="{back}" fill="none" stroke="#aab8d6" stroke-width="1.2" stroke-opacity="0.5" stroke-linecap="round"/>
  <g stroke-width="0.35" stroke-linejoin="round">
{quads}
  </g>
  <path d="{rim}" fill="none" stroke="#7a4818" stroke-width="1" stroke-linecap="round" stroke-linejoin="round"/>
  <path d="{front}" fill="none" stroke="#dce4f5" stroke-width="1.8" stroke-opacity="0.9" stroke-linecap="round"/>
</svg>
'''  # noqa: E501
    OUT.write_text(svg, encoding="utf-8")
    print(OUT, f"{len(svg):,} bytes")


if __name__ == "__main__":
    main()
