"""Animations of a scene: keyframed tracks of node properties, and the presets that make them.

An :class:`Animation` is ``frames`` pictures at ``fps`` and a list of :class:`Track`\\ s. A
track animates one property (:data:`ANIMATED`: the camera, an isosurface's isovalue or
opacity, a clip plane's origin or normal, a colour-by range, the scene's current time) of
one node, named by id (the camera's id is ``"camera"``, the scene's clock's
:data:`TIME_TARGET`), through :class:`Keyframe`\\ s: the value at frame ``k`` is the
keyframes' interpolation there, held before the first and after the last key.
:meth:`Animation.apply` sets frame ``k``'s values on the scene's nodes (each node updated at
once, so views never see a camera half moved); whatever draws the scene then draws frame
``k`` (:mod:`splineviz.render.movie` renders each one exactly).

Interpolation: scalars and points blend linearly, or with smooth-step easing
(``interpolation="smooth"``: zero speed at each key); a clip normal turns on the unit
sphere. The camera keeps its focal point, distance and orientation apart: the focal point
and the distance blend like scalars, and the camera's orientation (the frame of view
direction and view up) turns along the shortest rotation between the keys (quaternion
slerp, :class:`scipy.spatial.transform.Slerp`), so an orbit around an axis stays on its
circle at any elevation. Keys of one camera track are therefore less than half a turn apart
(the presets place one every quarter turn).

Animations are data (pydantic models, no code): sessions write them beside the views
(:mod:`splineviz.model.session`). Nothing here imports Qt or VTK.

Examples
--------
>>> from splineviz.model import Scene
>>> scene = Scene()
>>> scene.camera.update(position=(0.0, -4.0, 1.0), focal_point=(0.0, 0.0, 0.0),
...                     view_up=(0.0, 0.0, 1.0))
>>> anim = orbit(scene, degrees=360, frames=8)
>>> anim.apply(scene, 2)
>>> [round(v, 6) + 0.0 for v in scene.camera.position]
[4.0, 0.0, 1.0]
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from splineviz.core.errors import SplinevizError
from splineviz.core.registry import Registry
from splineviz.io.session import ID_PATTERN, MAX_MAGNITUDE
from splineviz.model.nodes import CameraNode, ClipPlaneNode, IsosurfaceNode, MeshNode, PointsNode

#: most frames of one animation (an hour at 25 fps)
MAX_FRAMES = 90_000
#: most tracks of an animation / keys of a track (sessions are bounded documents)
MAX_TRACKS = 64
MAX_KEYS = 10_000
#: the largest turn between two keys of a camera track that a preset makes (degrees)
CAMERA_KEY_STEP_DEG = 90.0
#: the target of a track of the scene's current time (like ``"camera"`` for the camera)
TIME_TARGET = "time"

Finite = Annotated[float, Field(allow_inf_nan=False, ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)]


class AnimationError(SplinevizError, ValueError):
    """An animation that cannot be made or applied (one sentence)."""


# ---------------------------------------------------------------------------- blending
def smooth_step(t: float) -> float:
    """``3t^2 - 2t^3``: 0 at 0, 1 at 1, zero speed at both."""
    return t * t * (3.0 - 2.0 * t)


def _lerp(a, b, t: float) -> tuple:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return tuple(float(v) for v in (1.0 - t) * a + t * b)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    n = float(np.linalg.norm(v))
    if n == 0.0:
        raise AnimationError("a direction of an animation is the zero vector")
    return v / n


def slerp_unit(a, b, t: float) -> tuple:
    """The unit vector a fraction ``t`` of the way from ``a`` to ``b`` along the great
    circle (``a`` and ``b`` need not be unit; opposite vectors turn about any axis
    perpendicular to ``a``)."""
    a, b = _unit(a), _unit(b)
    cos = float(np.clip(np.dot(a, b), -1.0, 1.0))
    if cos > 1.0 - 1e-12:
        return tuple(float(v) for v in a)
    if cos < -1.0 + 1e-12:  # half a turn: any perpendicular axis is as short
        axis = np.cross(a, (1.0, 0.0, 0.0) if abs(a[0]) < 0.9 else (0.0, 1.0, 0.0))
        b = _unit(axis)
        cos, t = 0.0, 2.0 * t
        if t > 1.0:
            a, b, t = b, -a, t - 1.0
    angle = math.acos(cos)
    s = math.sin(angle)
    v = (math.sin((1.0 - t) * angle) * a + math.sin(t * angle) * b) / s
    return tuple(float(x) for x in _unit(v))


def camera_frame(position, focal_point, view_up) -> np.ndarray:
    """``(3, 3)`` rotation whose columns are the camera's right, up and backward axes
    (backward: from the focal point to the eye; up: ``view_up`` made orthogonal to it)."""
    back = _unit(np.subtract(position, focal_point))
    up = np.asarray(view_up, dtype=float)
    up = up - np.dot(up, back) * back
    if np.linalg.norm(up) < 1e-9:
        raise AnimationError("the camera's view up is parallel to its view direction")
    up = _unit(up)
    return np.column_stack([np.cross(up, back), up, back])


def blend_camera(a, b, t: float) -> tuple:
    """Camera pose (the 10 numbers of :func:`_camera_read`) a fraction ``t`` from ``a``
    to ``b``: focal point, distance and view angle linear, orientation by quaternion
    slerp."""
    from scipy.spatial.transform import Rotation, Slerp

    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    fa, fb = a[3:6], b[3:6]
    da, db = np.linalg.norm(a[0:3] - fa), np.linalg.norm(b[0:3] - fb)
    ra = camera_frame(a[0:3], fa, a[6:9])
    rb = camera_frame(b[0:3], fb, b[6:9])
    r = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([ra, rb])))([t]).as_matrix()[0]
    focal = (1.0 - t) * fa + t * fb
    position = focal + ((1.0 - t) * da + t * db) * r[:, 2]
    angle = (1.0 - t) * a[9] + t * b[9]
    return tuple(float(v) for v in (*position, *focal, *r[:, 1], angle))


# ---------------------------------------------------------------------------- properties
@dataclass(frozen=True)
class AnimatedProperty:
    """How a track reads, writes and blends one kind of property.

    ``read(node) -> tuple`` of ``size`` floats; ``write(node, value) -> dict`` of the node
    fields to update; ``blend(a, b, t) -> tuple`` (``t`` in [0, 1], already eased)."""

    size: int
    nodes: tuple[type, ...]
    read: Callable
    write: Callable
    blend: Callable
    description: str


def _camera_read(cam) -> tuple:
    return (*cam.position, *cam.focal_point, *cam.view_up, cam.view_angle)


def _camera_write(_cam, v) -> dict:
    return {"position": tuple(v[0:3]), "focal_point": tuple(v[3:6]),
            "view_up": tuple(v[6:9]), "view_angle": v[9]}


class SceneTime:
    """The scene's current time as a track's node: ``time`` reads it, ``update(time=t)``
    moves the scene there (:meth:`~splineviz.model.scene.Scene.set_time`: every
    time-varying volume shows its last step at or before ``t``)."""

    kind = "scene time"

    def __init__(self, scene):
        self.scene = scene

    @property
    def time(self) -> float:
        return self.scene.time

    def update(self, fields=None, **more) -> None:
        fields = {**(fields or {}), **more}
        if "time" in fields:
            self.scene.set_time(fields["time"])


def _colour_range_write(node, v) -> dict:
    # a range the animation sets is the manual range (the automatic one follows the frame)
    lo, hi = float(v[0]), float(v[1])
    if not hi > lo:
        hi = lo + max(abs(lo), 1.0) * 1e-6
    return {"color_range": "manual", "color_min": lo, "color_max": hi}


#: property name -> :class:`AnimatedProperty` (the one declaration of what can be animated)
ANIMATED: Registry[AnimatedProperty] = Registry("animated property", {
    "camera": AnimatedProperty(
        10, (CameraNode,), _camera_read, _camera_write, blend_camera,
        "position, focal point, view up, view angle; orbits on the sphere"),
    "isovalue": AnimatedProperty(
        1, (IsosurfaceNode,), lambda n: (n.isovalue,), lambda n, v: {"isovalue": v[0]},
        _lerp, "an isosurface's isovalue"),
    "opacity": AnimatedProperty(
        1, (IsosurfaceNode, PointsNode, MeshNode), lambda n: (n.opacity,),
        lambda n, v: {"opacity": min(max(v[0], 1e-3), 1.0)}, _lerp, "an object's opacity"),
    "origin": AnimatedProperty(
        3, (ClipPlaneNode,), lambda n: tuple(n.origin), lambda n, v: {"origin": tuple(v)},
        _lerp, "a clip plane's origin"),
    "normal": AnimatedProperty(
        3, (ClipPlaneNode,), lambda n: tuple(n.normal), lambda n, v: {"normal": tuple(v)},
        slerp_unit, "a clip plane's normal (turns on the unit sphere)"),
    "color_range": AnimatedProperty(
        2, (IsosurfaceNode,), lambda n: (n.color_min, n.color_max), _colour_range_write,
        _lerp, "the range an isosurface's colour-by map spans (made manual)"),
    # keys at the steps' own times: a frame between two keys of neighbouring steps shows
    # the earlier step (set_time takes the last step at or before the time)
    "time": AnimatedProperty(
        1, (SceneTime,), lambda n: (n.time,), lambda n, v: {"time": v[0]}, _lerp,
        "the scene's current time (the step of every time-varying volume)"),
}, error=AnimationError)


# ---------------------------------------------------------------------------- the model
class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True)


class Keyframe(_Model):
    """The value of a track's property at ``frame`` (:data:`ANIMATED` says its layout)."""

    frame: Annotated[int, Field(ge=0, le=MAX_FRAMES)]
    value: Annotated[tuple[Finite, ...], Field(min_length=1, max_length=16)]


class Track(_Model):
    """Keyframes of one property of one node (``target``: a node id, or ``"camera"``)."""

    target: Annotated[str, Field(pattern=ID_PATTERN)]
    property: str
    interpolation: Literal["linear", "smooth"] = "linear"
    keys: Annotated[list[Keyframe], Field(min_length=1, max_length=MAX_KEYS)]

    @field_validator("property")
    @classmethod
    def _known(cls, v: str) -> str:
        if v not in ANIMATED:
            raise ValueError(f"unknown animated property {v[:64]!r}; choose one of "
                             f"{', '.join(ANIMATED)}")
        return v

    @field_validator("keys")
    @classmethod
    def _ordered(cls, keys, info):
        frames = [k.frame for k in keys]
        if any(b <= a for a, b in zip(frames, frames[1:], strict=False)):
            raise ValueError("keyframes must be in increasing frame order, one per frame")
        prop = ANIMATED.get(info.data.get("property"))
        if prop is not None and any(len(k.value) != prop.size for k in keys):
            raise ValueError(f"a {info.data['property']} keyframe holds {prop.size} "
                             "number(s)")
        return keys

    def value_at(self, frame: float) -> tuple:
        """The property's value at ``frame`` (held outside the keys)."""
        keys = self.keys
        if frame <= keys[0].frame:
            return keys[0].value
        if frame >= keys[-1].frame:
            return keys[-1].value
        frames = [k.frame for k in keys]
        i = int(np.searchsorted(frames, frame, side="right")) - 1
        a, b = keys[i], keys[i + 1]
        t = (frame - a.frame) / (b.frame - a.frame)
        if self.interpolation == "smooth":
            t = smooth_step(t)
        return ANIMATED[self.property].blend(a.value, b.value, t)

    def with_key(self, frame: int, value) -> Track:
        """A copy with the key at ``frame`` set to ``value`` (added or replaced)."""
        keys = [k for k in self.keys if k.frame != frame]
        keys.append(Keyframe(frame=frame, value=tuple(map(float, value))))
        return self.model_copy(update={"keys": sorted(keys, key=lambda k: k.frame)})


class Animation(_Model):
    """``frames`` pictures at ``fps``, made by ``tracks`` (see the module docstring)."""

    frames: Annotated[int, Field(ge=1, le=MAX_FRAMES)] = 120
    fps: Annotated[float, Field(gt=0.0, le=240.0, allow_inf_nan=False)] = 30.0
    tracks: Annotated[list[Track], Field(max_length=MAX_TRACKS)] = []

    @classmethod
    def make(cls, **values) -> Animation:
        """Validated construction that raises :class:`AnimationError` (one sentence)."""
        try:
            return cls(**values)
        except ValidationError as exc:
            e = exc.errors()[0]
            loc = ".".join(str(p) for p in e.get("loc", ()))
            raise AnimationError(f"animation {loc}: {e.get('msg', 'invalid')}".rstrip(".")
                                 ) from None

    @property
    def duration(self) -> float:
        """Seconds the animation lasts at its frame rate."""
        return self.frames / self.fps

    def check(self, scene) -> None:
        """Raise :class:`AnimationError` unless every track names a node of ``scene`` that
        has its property."""
        for track in self.tracks:
            node = _target(scene, track.target)
            prop = ANIMATED.lookup(track.property)
            if not isinstance(node, prop.nodes):
                raise AnimationError(f"a {track.property} track cannot animate "
                                     f"{node.kind} {track.target!r}")

    def values(self, frame: float) -> list[tuple[Track, tuple]]:
        """``(track, value)`` of every track at ``frame``."""
        return [(t, t.value_at(frame)) for t in self.tracks]

    def apply(self, scene, frame: float) -> None:
        """Set ``scene``'s animated properties to their values at ``frame`` (each node
        updated at once)."""
        if not 0 <= frame <= self.frames - 1 + 1e-9:
            raise AnimationError(f"frame {frame} is outside the animation's 0..{self.frames - 1}")
        self.check(scene)
        updates: dict[str, tuple] = {}
        for track, value in self.values(frame):
            node = _target(scene, track.target)
            fields = ANIMATED[track.property].write(node, value)
            updates.setdefault(track.target, (node, {}))[1].update(fields)
        for node, fields in updates.values():
            node.update(fields)

    def state_of(self, scene) -> dict:
        """The current values of the node fields the tracks set (for :meth:`restore`)."""
        state: dict[str, dict] = {}
        for track in self.tracks:
            node = _target(scene, track.target)
            prop = ANIMATED[track.property]
            fields = prop.write(node, prop.read(node))
            state.setdefault(track.target, {}).update(
                {k: getattr(node, k) for k in fields})
        return state

    def restore(self, scene, state: dict) -> None:
        """Put back the values :meth:`state_of` took (nodes removed since are skipped)."""
        for target, fields in state.items():
            if target in ("camera", TIME_TARGET) or target in scene:
                _target(scene, target).update(fields)

    def without(self, target: str) -> Animation:
        """This animation without the tracks of ``target`` (itself when it has none)."""
        tracks = [t for t in self.tracks if t.target != target]
        if len(tracks) == len(self.tracks):
            return self
        return self.model_copy(update={"tracks": tracks})

    def track(self, target: str, prop: str) -> Track | None:
        """The track of ``prop`` of ``target`` (None: none)."""
        return next((t for t in self.tracks if t.target == target and t.property == prop),
                    None)

    def add_key(self, scene, frame: int, target: str = "camera", prop: str = "camera"
                ) -> Animation:
        """A copy with a key at ``frame`` holding the current value of ``target``'s
        ``prop`` in ``scene`` (a new track when there is none): "add keyframe" from the
        view."""
        if not 0 <= frame < self.frames:
            raise AnimationError(f"frame {frame} is outside the animation's 0..{self.frames - 1}")
        node = _target(scene, target)
        value = ANIMATED.lookup(prop).read(node)
        old = self.track(target, prop)
        if old is None:
            new = Track(target=target, property=prop, keys=[Keyframe(frame=frame, value=value)])
            tracks = [*self.tracks, new]
        else:
            tracks = [t.with_key(frame, value) if t is old else t for t in self.tracks]
        return self.model_copy(update={"tracks": tracks})

    def __add__(self, other: Animation) -> Animation:
        """Both animations at once (the longer's length; ``other``'s tracks win where both
        animate the same property): a combination of presets."""
        if not isinstance(other, Animation):
            return NotImplemented
        mine = [t for t in self.tracks if other.track(t.target, t.property) is None]
        return Animation.make(frames=max(self.frames, other.frames), fps=self.fps,
                              tracks=[*mine, *other.tracks])


def _target(scene, target: str):
    if target == "camera":
        return scene.camera
    if target == TIME_TARGET:
        if not scene.time_steps():
            raise AnimationError("the animation plays the scene's time, but the scene holds "
                                 "no time-varying volume")
        return SceneTime(scene)
    if target not in scene:
        raise AnimationError(f"the animation animates {target!r}, which is not in the scene")
    return scene.get(target)


# ---------------------------------------------------------------------------- presets
def _frames(frames: int) -> int:
    if not isinstance(frames, int | np.integer) or not 1 <= frames <= MAX_FRAMES:
        raise AnimationError(f"an animation has 1 to {MAX_FRAMES} frames, got {frames!r}")
    return int(frames)


def _end_frame(frames: int, closed: bool) -> int:
    """The frame of a preset's last key: one past the last frame for a closed loop (a
    full turn, whose last frame must not repeat the first), else the last frame."""
    return frames if closed else max(frames - 1, 1)


def _rotation(axis, degrees: float) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_rotvec(_unit(axis) * math.radians(degrees)).as_matrix()


def orbit(scene, degrees: float = 360.0, frames: int = 120, axis=None,
          fps: float = 30.0) -> Animation:
    """A turntable: the camera turns ``degrees`` about ``axis`` (default: its view up)
    through the focal point, at constant speed, over ``frames`` frames. A whole number of
    turns loops: the last frame is one step before the first again."""
    frames = _frames(frames)
    degrees = float(degrees)
    if not math.isfinite(degrees):
        raise AnimationError(f"an orbit needs a finite angle, got {degrees}")
    cam = scene.camera
    axis = _unit(cam.view_up if axis is None else axis)
    closed = degrees != 0.0 and math.isclose(degrees % 360.0, 0.0, abs_tol=1e-9)
    end = _end_frame(frames, closed)
    steps = max(1, math.ceil(abs(degrees) / CAMERA_KEY_STEP_DEG))
    # keys on frames that split the turn evenly (a key's angle follows its frame exactly,
    # so the camera turns at one speed across keys)
    key_frames = sorted({round(end * i / steps) for i in range(steps + 1)})
    focal = np.asarray(cam.focal_point, dtype=float)
    pos, up = np.asarray(cam.position, dtype=float), np.asarray(cam.view_up, dtype=float)
    keys = []
    for f in key_frames:
        r = _rotation(axis, degrees * f / end)
        keys.append(Keyframe(frame=f, value=(*(focal + r @ (pos - focal)), *focal, *(r @ up),
                                             cam.view_angle)))
    return Animation.make(frames=frames, fps=fps,
                          tracks=[Track(target="camera", property="camera", keys=keys)])


def _isosurface(scene, isosurface):
    if isosurface is None:
        if not scene.isosurfaces:
            raise AnimationError("the scene has no isosurface to animate")
        return scene.isosurfaces[0]
    return scene.get(isosurface) if isinstance(isosurface, str) else isosurface


def isovalue_sweep(scene, start: float, stop: float, frames: int = 120, isosurface=None,
                   interpolation: str = "linear", fps: float = 30.0) -> Animation:
    """The isovalue of ``isosurface`` (default: the scene's first) from ``start`` on the
    first frame to ``stop`` on the last."""
    frames = _frames(frames)
    iso = _isosurface(scene, isosurface)
    end = _end_frame(frames, False)
    return Animation.make(frames=frames, fps=fps, tracks=[Track(
        target=iso.id, property="isovalue", interpolation=interpolation,
        keys=[Keyframe(frame=0, value=(float(start),)),
              Keyframe(frame=end, value=(float(stop),))])])


#: clip-sweep axes: name -> the normal of the moving plane (it keeps the side it points to)
SWEEP_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0),
              "-x": (-1.0, 0.0, 0.0), "-y": (0.0, -1.0, 0.0), "-z": (0.0, 0.0, -1.0)}


def clip_sweep(scene, axis: str = "x", frames: int = 120, volume=None, plane=None,
               fps: float = 30.0) -> Animation:
    """A clip plane moving through the volume along ``axis`` (a key of
    :data:`SWEEP_AXES`): on the first frame the whole object shows, on the last it is cut
    away. Uses ``plane`` (a clip plane id or node) or adds a scene-wide plane (``volume``:
    one of the volume's own) to the scene."""
    frames = _frames(frames)
    key = str(axis).lower()
    if key not in SWEEP_AXES:
        raise AnimationError(f"unknown clip-sweep axis {axis!r}; choose one of "
                             f"{', '.join(SWEEP_AXES)}")
    normal = np.asarray(SWEEP_AXES[key])
    if isinstance(volume, str):
        volume = scene.get(volume)
    bounds = volume.bounds if volume is not None else scene.bounds()
    if bounds is None:
        raise AnimationError("a clip sweep needs data in the scene")
    b = np.asarray(bounds, dtype=float)
    centre = b.mean(axis=1)
    a = int(np.argmax(np.abs(normal)))
    # the plane keeps the side its normal points to: it starts behind the box (all kept)
    # and ends past it (all cut)
    lo, hi = (b[a, 0], b[a, 1]) if normal[a] > 0 else (b[a, 1], b[a, 0])
    start, stop = centre.copy(), centre.copy()
    start[a], stop[a] = lo, hi
    if plane is None:
        plane = scene.add_clip_plane(tuple(start), tuple(normal), volume=volume,
                                     show_widget=False, name=f"clip sweep {key}")
    elif isinstance(plane, str):
        plane = scene.get(plane)
    plane.update(origin=tuple(map(float, start)), normal=tuple(map(float, normal)),
                 enabled=True)
    end = _end_frame(frames, False)
    keys = [Keyframe(frame=0, value=tuple(start)), Keyframe(frame=end, value=tuple(stop))]
    return Animation.make(frames=frames, fps=fps,
                          tracks=[Track(target=plane.id, property="origin", keys=keys)])


def time_playback(scene, start: int = 0, stop: int = -1, frames_per_step: int | None = 1,
                  frames: int | None = None, fps: float = 30.0) -> Animation:
    """The scene's time steps ``start`` to ``stop`` (indices of
    :meth:`~splineviz.model.scene.Scene.time_steps`, both shown; negative counts from the
    end), in order.

    Each step lasts ``frames_per_step`` frames; ``None`` matches the movie to the scene's
    play rate (``round(fps / scene.play_rate)`` frames a step, at least one, so the movie
    plays the steps as fast as the time toolbar does). ``frames`` (which overrides
    ``frames_per_step``) spreads the steps evenly over that many frames instead (frame
    ``k`` shows step ``start + floor(k * steps / frames)``; fewer frames than steps skip
    some). The track keys the step's own time on the first frame of each step."""
    steps = scene.time_steps()
    if not steps:
        raise AnimationError("time playback needs a time-varying volume in the scene")
    n = len(steps)
    first, last = (int(i) + n if int(i) < 0 else int(i) for i in (start, stop))
    if not 0 <= first <= last < n:
        raise AnimationError(f"the scene has {n} time step(s) (0 to {n - 1}); steps "
                             f"{start} to {stop} are not a range of them")
    count = last - first + 1
    if frames is None:
        if frames_per_step is None:
            frames_per_step = max(1, round(float(fps) / scene.play_rate))
        if not isinstance(frames_per_step, int | np.integer) or frames_per_step < 1:
            raise AnimationError(f"a step lasts 1 or more frames, got {frames_per_step!r}")
        frames = count * int(frames_per_step)
    frames = _frames(frames)
    keys, shown = [], None
    for k in range(frames):
        step = first + k * count // frames
        if step != shown:
            keys.append(Keyframe(frame=k, value=(steps[step],)))
            shown = step
    return Animation.make(frames=frames, fps=fps, tracks=[
        Track(target=TIME_TARGET, property="time", keys=keys)])


#: preset name -> function(scene, frames=..., **options) -> Animation
PRESETS = {"orbit": orbit, "isovalue sweep": isovalue_sweep, "clip sweep": clip_sweep,
           "time playback": time_playback}


def preset_animation(scene, *, orbit_degrees: float | None = None, iso_sweep=None,
                     clip_axis: str | None = None, all_times: bool = False,
                     frames: int | None = 120, fps: float = 30.0) -> Animation | None:
    """The combination of the presets asked for (None: none asked): a playback of every
    time step (``all_times``), a turntable of ``orbit_degrees``, an isovalue sweep
    ``(start, stop)`` of the first isosurface and a clip sweep along ``clip_axis``, all
    over ``frames`` frames (what ``splineviz movie``'s flags and ``sv.movie``'s keywords
    make). ``frames=None``: 120, or with ``all_times`` one frame per step."""
    parts = []
    if all_times:
        parts.append(time_playback(scene, frames=frames, fps=fps))
        frames = parts[0].frames
    frames = 120 if frames is None else frames
    if orbit_degrees is not None:
        parts.append(orbit(scene, orbit_degrees, frames=frames, fps=fps))
    if iso_sweep is not None:
        start, stop = iso_sweep
        parts.append(isovalue_sweep(scene, start, stop, frames=frames, fps=fps))
    if clip_axis is not None:
        parts.append(clip_sweep(scene, clip_axis, frames=frames, fps=fps))
    if not parts:
        return None
    out = parts[0]
    for part in parts[1:]:
        out = out + part
    return out
