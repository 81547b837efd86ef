"""The simulated intelligent space of book ch. 12: a scene file and its typed form.

Conventions (ch12.md §1.2, §1.6):

- world frame in metres and radians; the room spans ``[-W/2, W/2] x [-H/2, H/2]`` (the chapter's
  Table 1 poses are centred on the room);
- a laser range finder's pose ``(x, y, theta)`` maps its local scan points to the world:
  ``p_world = R(theta) p_local + (x, y)`` (Eq. 2);
- cameras follow OpenCV: ``x_cam = R(rvec) X + tvec``, pixels ``u = f x/z + cx`` with one optional
  radial coefficient ``k1``;
- the robot's start pose is known (the chapter's robot knows where it enters).

``marker_height`` may be one height or a list.  One height puts every marker on a plane, and a
plane cannot give the principal point (Tsai needs non-coplanar points, ch12.md §1.6, pitfall 7): the
calibration then fixes ``(cx, cy)`` at the image centre.  A list stands in for the chapter's two
robots of different heights (a mast carrying one marker per height).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError, SourceError


@dataclass(frozen=True)
class LrfPose:
    x: float
    y: float
    theta: float


@dataclass(frozen=True)
class CameraSpec:
    rvec: tuple[float, float, float]
    tvec: tuple[float, float, float]
    f: float
    cx: float
    cy: float
    width: int = 320
    height: int = 240
    k1: float = 0.0

    def K(self) -> np.ndarray:
        return np.array([[self.f, 0, self.cx], [0, self.f, self.cy], [0, 0, 1.0]])

    def dist(self) -> np.ndarray:
        return np.array([self.k1, 0, 0, 0, 0], dtype=np.float64)


@dataclass(frozen=True)
class RobotSpec:
    start: tuple[float, float, float] = (3.0, 0.0, np.pi)
    duration_s: float = 120.0
    rate_hz: float = 10.0
    marker_height: tuple[float, ...] = (0.30, 0.80)
    radius: float = 0.19          # ch12.md §1.3: d = 0.15 m implies rho ~ 0.19 m
    tag_offset: float = 0.15      # L of Eq. (9)
    speed: float = 0.3            # m/s (ch12.md §5.2)


@dataclass(frozen=True)
class HumanSpec:
    start: tuple[float, float]
    end: tuple[float, float]
    speed: float = 1.0


@dataclass(frozen=True)
class NoiseSpec:
    lrf_range: float = 0.01       # m
    odometry: float = 0.02        # sigma_v in m/s; sigma_omega = 2.5 * odometry rad/s (ch12.md §2 ratio)
    pixel: float = 0.5            # px
    ultrasound: float = 0.05      # m per axis (ch12.md §2)


@dataclass(frozen=True)
class Scene:
    room: tuple[float, float]
    lrfs: tuple[LrfPose, ...]
    cameras: tuple[CameraSpec, ...]
    robot: RobotSpec = field(default_factory=RobotSpec)
    noise: NoiseSpec = field(default_factory=NoiseSpec)
    humans: tuple[HumanSpec, ...] = ()

    def to_dict(self) -> dict:
        return {"room": list(self.room),
                "lrfs": [{"x": p.x, "y": p.y, "theta": p.theta} for p in self.lrfs],
                "cameras": [{"rvec": list(c.rvec), "tvec": list(c.tvec), "f": c.f, "cx": c.cx, "cy": c.cy,
                             "width": c.width, "height": c.height, "k1": c.k1} for c in self.cameras],
                "robot": {"start": list(self.robot.start), "duration_s": self.robot.duration_s,
                          "rate_hz": self.robot.rate_hz, "marker_height": list(self.robot.marker_height),
                          "radius": self.robot.radius, "tag_offset": self.robot.tag_offset,
                          "speed": self.robot.speed},
                "noise": {"lrf_range": self.noise.lrf_range, "odometry": self.noise.odometry,
                          "pixel": self.noise.pixel, "ultrasound": self.noise.ultrasound},
                "humans": [{"start": list(h.start), "end": list(h.end), "speed": h.speed} for h in self.humans]}


def look_at(eye, target, up=(0.0, 0.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV ``(rvec, tvec)`` of a camera at ``eye`` whose optical axis points at ``target``."""
    import cv2

    eye, target = np.asarray(eye, float), np.asarray(target, float)
    z = target - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, np.asarray(up, float))
    if np.linalg.norm(x) < 1e-9:
        x = np.array([1.0, 0, 0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    R = np.stack([x, y, z])           # rows: camera axes in world coordinates
    rvec, _ = cv2.Rodrigues(R)
    return rvec.ravel(), -R @ eye


def ceiling_camera(center_xy, *, yaw: float, height: float = 2.6, tilt_deg: float = 50.0, f: float = 260.0,
                   size=(320, 240), k1: float = 0.0) -> CameraSpec:
    """A ceiling camera looking at ``center_xy`` on the floor with its axis ``tilt_deg`` below horizontal."""
    tilt = np.radians(tilt_deg)
    back = height / np.tan(tilt)
    eye = (center_xy[0] - back * np.cos(yaw), center_xy[1] - back * np.sin(yaw), height)
    rvec, tvec = look_at(eye, (center_xy[0], center_xy[1], 0.0))
    return CameraSpec(tuple(map(float, rvec)), tuple(map(float, tvec)), float(f), size[0] / 2, size[1] / 2,
                      int(size[0]), int(size[1]), float(k1))


def default_scene() -> Scene:
    """The chapter's experiment (ch12.md §5.2): a 7 m x 6 m room, the three LRFs at Table 1's manual
    poses, four ceiling cameras each seeing about 4 m x 4 m, markers at 0.30 m and 0.80 m."""
    lrfs = (LrfPose(-1.95, 1.00, -0.15), LrfPose(0.95, 1.02, -2.54), LrfPose(0.20, -1.97, 1.60))
    cams = tuple(ceiling_camera(c, yaw=y) for c, y in
                 [((-1.5, 1.3), 0.3), ((1.5, 1.3), 2.5), ((1.5, -1.3), -2.3), ((-1.5, -1.3), -0.9)])
    return Scene(room=(7.0, 6.0), lrfs=lrfs, cameras=cams)


def random_scene(seed: int) -> Scene:
    """A random room (6-9 m x 5-8 m) with 3 LRFs and 4 ceiling cameras, for unseen-configuration tests."""
    rng = np.random.default_rng(seed)
    W, H = rng.uniform(6, 9), rng.uniform(5, 8)
    lrfs = []
    for _ in range(3):
        x, y = rng.uniform(-W / 2 + 0.3, W / 2 - 0.3), rng.uniform(-H / 2 + 0.3, H / 2 - 0.3)
        toward = np.arctan2(-y, -x) + rng.uniform(-0.6, 0.6)   # roughly facing the room
        lrfs.append(LrfPose(float(x), float(y), float(np.arctan2(np.sin(toward), np.cos(toward)))))
    cams = []
    for sx, sy in [(-1, 1), (1, 1), (1, -1), (-1, -1)]:
        c = (sx * W / 4 + rng.uniform(-0.3, 0.3), sy * H / 4 + rng.uniform(-0.3, 0.3))
        cams.append(ceiling_camera(c, yaw=float(rng.uniform(-np.pi, np.pi)), height=float(rng.uniform(2.4, 3.0)),
                                   tilt_deg=float(rng.uniform(45, 65)), f=float(rng.uniform(230, 290))))
    start = (W / 2 - 0.5, 0.0, np.pi)
    return Scene(room=(float(W), float(H)), lrfs=tuple(lrfs), cameras=tuple(cams),
                 robot=RobotSpec(start=start))


def _floats(v, n: int, what: str) -> tuple[float, ...]:
    try:
        out = tuple(float(a) for a in v)
    except (TypeError, ValueError):
        raise InputError(f"{what}: expected {n} numbers, got {v!r}") from None
    if len(out) != n or not all(np.isfinite(out)):
        raise InputError(f"{what}: expected {n} finite numbers, got {v!r}")
    return out


def scene_from_dict(d: dict, where: str = "scene") -> Scene:
    if not isinstance(d, dict):
        raise InputError(f"{where}: expected a JSON object")
    try:
        W, H = _floats(d["room"], 2, f"{where}: room")
        if W <= 0 or H <= 0:
            raise InputError(f"{where}: room must have positive width and height")
        lrfs = tuple(LrfPose(*_floats((p["x"], p["y"], p["theta"]), 3, f"{where}: lrfs[{i}]"))
                     for i, p in enumerate(d.get("lrfs", [])))
        cams = []
        for i, c in enumerate(d.get("cameras", [])):
            rv = _floats(c["rvec"], 3, f"{where}: cameras[{i}].rvec")
            tv = _floats(c["tvec"], 3, f"{where}: cameras[{i}].tvec")
            f, cx, cy = _floats((c["f"], c["cx"], c["cy"]), 3, f"{where}: cameras[{i}]")
            w, h = int(c.get("width", 320)), int(c.get("height", 240))
            if f <= 0 or w < 16 or h < 16:
                raise InputError(f"{where}: cameras[{i}]: f must be > 0 and the image at least 16x16")
            cams.append(CameraSpec(rv, tv, f, cx, cy, w, h, float(c.get("k1", 0.0))))
        r = d.get("robot", {})
        mh = r.get("marker_height", RobotSpec.marker_height)
        mh = (float(mh),) if np.isscalar(mh) else tuple(float(a) for a in mh)
        robot = RobotSpec(start=_floats(r.get("start", (W / 2 - 0.5, 0.0, np.pi)), 3, f"{where}: robot.start"),
                          duration_s=float(r.get("duration_s", 120.0)), rate_hz=float(r.get("rate_hz", 10.0)),
                          marker_height=mh, radius=float(r.get("radius", 0.19)),
                          tag_offset=float(r.get("tag_offset", 0.15)), speed=float(r.get("speed", 0.3)))
        if robot.duration_s <= 5 or robot.rate_hz <= 0 or not mh:
            raise InputError(f"{where}: robot needs duration_s > 5, rate_hz > 0 and a marker height")
        n = d.get("noise", {})
        noise = NoiseSpec(lrf_range=float(n.get("lrf_range", 0.01)), odometry=float(n.get("odometry", 0.02)),
                          pixel=float(n.get("pixel", 0.5)), ultrasound=float(n.get("ultrasound", 0.05)))
        if min(noise.lrf_range, noise.odometry, noise.pixel, noise.ultrasound) < 0:
            raise InputError(f"{where}: noise levels must be >= 0")
        humans = tuple(HumanSpec(_floats(h["start"], 2, f"{where}: humans[{i}].start"),
                                 _floats(h["end"], 2, f"{where}: humans[{i}].end"), float(h.get("speed", 1.0)))
                       for i, h in enumerate(d.get("humans", [])))
    except KeyError as exc:
        raise InputError(f"{where}: missing key {exc.args[0]!r}") from None
    except (TypeError, ValueError) as exc:
        if isinstance(exc, InputError):
            raise
        raise InputError(f"{where}: {exc}") from None
    x0, y0 = robot.start[:2]
    if abs(x0) > W / 2 or abs(y0) > H / 2:
        raise InputError(f"{where}: robot.start lies outside the room")
    for i, p in enumerate(lrfs):
        if abs(p.x) > W / 2 or abs(p.y) > H / 2:
            raise InputError(f"{where}: lrfs[{i}] lies outside the room")
    return Scene((W, H), lrfs, tuple(cams), robot, noise, humans)


def load_scene(path: str | Path) -> Scene:
    p = Path(path)
    if not p.is_file():
        raise SourceError(f"{path}: no such file")
    try:
        d = json.loads(p.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: not valid JSON ({exc})") from None
    return scene_from_dict(d, where=str(path))
