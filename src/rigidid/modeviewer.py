"""An interactive 3D view of the mode shapes for the self-contained HTML report: turn it, animate it.

:func:`mode_viewer_html` returns one HTML fragment: a ``<canvas>``, its controls, the
shapes as inline JSON and a small inline script (below, written for rigidid: no
library, no network). The reader drags to turn the view, picks a mode, plays or
pauses the motion and sets its amplitude. Each mode is drawn as the rigid-body
motion of the CG that best fits its readings (``Identification.mode_shapes_cg``),
moving every sensor point by ``Re(phi e^(i t))``: the translation of the CG plus
the rotation times the point's offset from it (eqs. (11)-(14) of [1]).

Labels (the CG, the axes and the sensors) are HTML elements over the canvas,
placed at each frame where they overlap no other label and no point; a label that
finds no free place is left out (the sensors are listed in the layout table). So
a browser can measure them: every label has the class ``rv-label``.

In print the viewer is hidden (``.rv-noprint``): the static figure of the mode
shapes stands for it.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from rigidid.core.geometry import sensor_outline

__all__ = ["VIEWER_CSS", "mode_motions", "mode_viewer_html"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]


def mode_motions(shapes_cg: CArray, points: Array, cg: Array) -> CArray:
    """Complex translations of `points` for each mode's CG motion, largest point motion scaled to 1.

    Parameters
    ----------
    shapes_cg : ndarray of complex, shape (6, n)
        Rigid-body motion of the CG per mode (translations, then rotations in rad).
    points : ndarray, shape (k, 3)
        Points to move (length).
    cg : ndarray, shape (3,)

    Returns
    -------
    ndarray of complex, shape (n, k, 3)
        ``x + theta x (r - g)`` per mode and point (eq. (12) of [1]), divided by the
        largest point motion, and turned so that motion is real (phase 0 shows it).
    """
    offsets = np.asarray(points, dtype=float) - np.asarray(cg, dtype=float)[None, :]
    out = np.zeros((shapes_cg.shape[1], offsets.shape[0], 3), dtype=complex)
    for k in range(shapes_cg.shape[1]):
        phi = shapes_cg[:, k]
        motion = phi[:3][None, :] + np.cross(phi[3:][None, :], offsets)
        flat = motion.reshape(-1)
        peak = flat[np.argmax(np.abs(flat))] if flat.size else 0.0
        if abs(peak) > 0.0:
            motion = motion / peak
            motion = motion / max(float(np.max(np.linalg.norm(np.abs(motion), axis=1))), 1e-300)
        out[k] = motion
    return out


VIEWER_CSS = """
.rv { position: relative; max-width: 900px; }
.rv canvas { width: 100%; height: auto; border: 1px solid #e3e7ec; touch-action: none; cursor: grab; display: block; }
.rv .rv-stage { position: relative; }
.rv .rv-label { position: absolute; font-size: 12px; line-height: 14px; white-space: nowrap; pointer-events: none;
                color: #1a1a1a; background: rgba(255,255,255,0.75); padding: 0 2px; }
.rv .rv-controls { display: flex; flex-wrap: wrap; gap: 10px 16px; align-items: center; margin: 6px 0;
                   font-size: 14px; }
.rv .rv-title { font-weight: 600; }
@media print { .rv-noprint { display: none !important; } }
"""

# The viewer: orthographic projection turned by azimuth and elevation; the mode's points at phase
# t move by Re(m e^{it}) * amplitude * size; labels placed greedily in one of eight spots around
# their point where the box meets no earlier label and no point marker, else hidden.
_SCRIPT = r"""
(function () {
  const root = document.getElementById("__ID__");
  const data = JSON.parse(root.querySelector("script[type='application/json']").textContent);
  const canvas = root.querySelector("canvas"), stage = root.querySelector(".rv-stage");
  const pick = root.querySelector("select"), play = root.querySelector("button.rv-play");
  const amp = root.querySelector("input[type=range]"), title = root.querySelector(".rv-title");
  const ctx = canvas.getContext("2d");
  let az = -0.9, el = 0.45, phase = 0, running = true, mode = 0, last = null, labels = [];
  const n = data.points.length, centre = [0, 1, 2].map(i => data.points.reduce((s, p) => s + p[i], 0) / n);
  const size = Math.max(...[0, 1, 2].map(i => Math.max(...data.points.map(p => p[i])) -
                                              Math.min(...data.points.map(p => p[i])))) || 1;
  function makeLabel(text, cls) {
    const span = document.createElement("span"); span.className = "rv-label " + cls; span.textContent = text;
    stage.appendChild(span); return span;
  }
  labels.push({el: makeLabel("CG", "rv-cg"), point: n - 1});
  data.axes.forEach((a, i) => { const l = makeLabel(a, "rv-axis"); l.style.color = data.colours[i];
    labels.push({el: l, axis: i}); });
  data.sensors.forEach((s, i) => labels.push({el: makeLabel(s, "rv-sensor"), point: i}));
  function project(p, scale, w, h) {
    const x = p[0] - centre[0], y = p[1] - centre[1], z = p[2] - centre[2];
    const ca = Math.cos(az), sa = Math.sin(az), ce = Math.cos(el), se = Math.sin(el);
    const u = ca * x - sa * y, v = sa * x + ca * y;
    return [w / 2 + scale * u, h / 2 - scale * (ce * z - se * v), ce * v + se * z];
  }
  function resize() {
    const ratio = window.devicePixelRatio || 1, w = canvas.clientWidth, h = Math.round(w * 0.62);
    canvas.style.height = h + "px"; canvas.width = Math.round(w * ratio); canvas.height = Math.round(h * ratio);
    ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
  }
  function ring(pts, colour, dash, width) {
    ctx.strokeStyle = colour; ctx.lineWidth = width; ctx.setLineDash(dash); ctx.beginPath();
    data.outline.forEach((k, i) => (i ? ctx.lineTo(pts[k][0], pts[k][1]) : ctx.moveTo(pts[k][0], pts[k][1])));
    ctx.stroke(); ctx.setLineDash([]);
    ctx.strokeStyle = colour; ctx.lineWidth = 0.8;
    for (let k = 0; k < n - 1; k++) { ctx.beginPath(); ctx.moveTo(pts[n-1][0], pts[n-1][1]);
      ctx.lineTo(pts[k][0], pts[k][1]); ctx.stroke(); }
  }
  function dots(pts, colour) {
    ctx.fillStyle = colour;
    pts.forEach((p, k) => { ctx.beginPath(); ctx.arc(p[0], p[1], k === n - 1 ? 6 : 3.5, 0, 2 * Math.PI); ctx.fill(); });
  }
  function place(items, markers, w, h) {
    const boxes = [];
    const free = b => b.x >= 0 && b.y >= 0 && b.x + b.w <= w && b.y + b.h <= h &&
      !boxes.some(o => b.x < o.x + o.w && o.x < b.x + b.w && b.y < o.y + o.h && o.y < b.y + b.h) &&
      !markers.some(m => m[0] + 5 > b.x && m[0] - 5 < b.x + b.w && m[1] + 5 > b.y && m[1] - 5 < b.y + b.h);
    items.forEach(({el, at}) => {
      el.style.display = ""; const bw = el.offsetWidth, bh = el.offsetHeight;
      const spots = [[8, -bh - 4], [8, 4], [-bw - 8, -bh - 4], [-bw - 8, 4], [-bw / 2, -bh - 8], [-bw / 2, 8],
                     [10, -bh / 2], [-bw - 10, -bh / 2]];
      const spot = spots.map(([dx, dy]) => ({x: at[0] + dx, y: at[1] + dy, w: bw, h: bh})).find(free);
      if (spot) { boxes.push(spot); el.style.left = spot.x + "px"; el.style.top = spot.y + "px"; }
      else el.style.display = "none";
    });
  }
  function draw() {
    const w = canvas.clientWidth, h = canvas.clientHeight, scale = 0.75 * Math.min(w, h) / size;
    const a = Number(amp.value) / 100 * 0.3 * size, m = data.modes[mode];
    const c = Math.cos(phase), s = Math.sin(phase);
    const moved = data.points.map((p, k) => p.map((x, i) => x + a * (m.re[k][i] * c - m.im[k][i] * s)));
    const rest = data.points.map(p => project(p, scale, w, h)), now = moved.map(p => project(p, scale, w, h));
    ctx.clearRect(0, 0, w, h);
    ring(rest, "#8a97a5", [5, 4], 1.0); dots(rest, "#b3bdc8");
    ring(now, "#c0392b", [], 1.8); dots(now, "#c0392b");
    const origin = [46, h - 46], ends = data.axes.map((_, i) => {
      const e = [0, 0, 0]; e[i] = 1; const p = project(e.map((v, j) => centre[j] + v), 30, 0, 0);
      return [origin[0] + p[0], origin[1] + p[1]];
    });
    ends.forEach((e, i) => { ctx.strokeStyle = data.colours[i]; ctx.lineWidth = 2; ctx.beginPath();
      ctx.moveTo(origin[0], origin[1]); ctx.lineTo(e[0], e[1]); ctx.stroke(); });
    const items = labels.map(l => ({el: l.el, at: l.axis === undefined ? now[l.point] : ends[l.axis]}));
    place(items, now.concat(ends), w, h);
  }
  function frame(t) {
    if (running && last !== null) phase = (phase + (t - last) / 1000 * 2 * Math.PI * 0.6) % (2 * Math.PI);
    last = t; draw(); if (running) requestAnimationFrame(frame); else last = null;
  }
  function choose() {
    mode = Number(pick.value); title.textContent = data.modes[mode].title; draw();
  }
  let drag = null;
  canvas.addEventListener("pointerdown", e => {
    drag = [e.clientX, e.clientY, az, el]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener("pointermove", e => { if (!drag) return;
    az = drag[2] + (e.clientX - drag[0]) * 0.01;
    el = Math.max(-1.5, Math.min(1.5, drag[3] + (e.clientY - drag[1]) * 0.01)); draw(); });
  canvas.addEventListener("pointerup", () => { drag = null; });
  pick.addEventListener("change", choose);
  amp.addEventListener("input", draw);
  play.addEventListener("click", () => { running = !running; play.textContent = running ? "pause" : "play";
    if (running) requestAnimationFrame(frame); });
  root.querySelector("button.rv-reset").addEventListener("click", () => { az = -0.9; el = 0.45; draw(); });
  window.addEventListener("resize", () => { resize(); draw(); });
  resize(); choose();
  if (data.still) { running = false; play.textContent = "play"; } else requestAnimationFrame(frame);
})();
"""


def mode_viewer_html(
    positions: Array,
    sensor_ids: Sequence[str],
    cg: Array,
    shapes_cg: CArray,
    titles: Sequence[str],
    length: str,
    *,
    element_id: str = "rigidid-modes",
    still: bool = False,
) -> str:
    """The interactive mode-shape viewer as one HTML fragment (canvas, controls, inline data and script).

    Parameters
    ----------
    positions : ndarray, shape (p, 3)
        Sensor positions (length).
    sensor_ids : sequence of str, length p
    cg : ndarray, shape (3,)
    shapes_cg : ndarray of complex, shape (6, n)
        Each mode's rigid-body motion of the CG.
    titles : sequence of str, length n
        One line per mode (label, frequency, damping, what moves).
    length : str
        Length unit, named in the caption.
    element_id : str
        The ``id`` of the viewer's element (unique in the page).
    still : bool
        Start paused (for screenshots); the reader's "play" starts it.

    Returns
    -------
    str
    """
    pos, names = _nodes(np.asarray(positions, dtype=float).reshape(-1, 3), [str(s) for s in sensor_ids])
    points = np.vstack([pos, np.asarray(cg, dtype=float)[None, :]])
    motions = mode_motions(shapes_cg, points, np.asarray(cg, dtype=float))
    data = {
        "points": np.round(points, 9).tolist(),
        "sensors": names,
        "outline": [int(k) for k in sensor_outline(pos)],
        "axes": ["x", "y", "z"],
        "colours": ["#2e8b57", "#d68910", "#7d3c98"],
        "modes": [
            {"title": str(t), "re": np.round(m.real, 9).tolist(), "im": np.round(m.imag, 9).tolist()}
            for t, m in zip(titles, motions, strict=True)
        ],
        "still": bool(still),
    }
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    options = "".join(f'<option value="{k}">{_escape(t)}</option>' for k, t in enumerate(titles))
    return (
        f'<div class="rv rv-noprint" id="{element_id}">'
        f'<div class="rv-controls"><label>mode <select>{options}</select></label>'
        '<button type="button" class="rv-play">pause</button>'
        '<label>amplitude <input type="range" min="0" max="100" value="50"></label>'
        '<button type="button" class="rv-reset">reset view</button></div>'
        '<p class="rv-title"></p><div class="rv-stage"><canvas width="860" height="533"></canvas></div>'
        f'<p class="meta">Drag to turn the view. Grey, dashed: the sensor outline at rest; red: moving with the '
        f"mode (the largest sensor motion is 30 % of the layout size at full amplitude); the large dot is the CG; "
        f"axes x, y, z bottom left; positions in {_escape(length)}.</p>"
        f'<script type="application/json">{payload}</script>'
        f"<script>{_SCRIPT.replace('__ID__', element_id)}</script></div>"
    )


def _nodes(positions: Array, ids: list[str]) -> tuple[Array, list[str]]:
    """Distinct sensor positions and one label each: the ids there, sharing their common prefix (``1+x/y/z``)."""
    groups: list[list[int]] = []
    for i, p in enumerate(positions):
        for group in groups:
            if np.allclose(positions[group[0]], p, rtol=0.0, atol=1e-9 * (1.0 + float(np.abs(p).max()))):
                group.append(i)
                break
        else:
            groups.append([i])
    names = []
    for group in groups:
        members = [ids[i] for i in group]
        prefix = _common_prefix(members) if len(members) > 1 else ""
        names.append(prefix + "/".join(m[len(prefix) :] for m in members) if prefix else ", ".join(members))
    return positions[[g[0] for g in groups]], names


def _common_prefix(words: list[str]) -> str:
    """The characters all `words` start with."""
    first = words[0]
    n = 0
    while n < len(first) and all(len(w) > n and w[n] == first[n] for w in words):
        n += 1
    return first[:n]


def _escape(text: str) -> str:
    import html

    return html.escape(str(text), quote=True)
