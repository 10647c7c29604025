#!/usr/bin/python3
"""An external pose estimator for rig: OpenCV's solvePnP on the frame.

Speaks protocol rig-estimator version 1 (docs/external-estimators.md) on
stdin/stdout, one JSON object per line. For every frame it reads the PNG rig
wrote (and checks its size against the calibration), takes the marker
corners rig detected, and solves the pose with cv2.solvePnP (SOLVEPNP_IPPE,
Collins and Bartoli, "Infinitesimal Plane-Based Pose Estimation", IJCV 2014,
DOI 10.1007/s11263-014-0725-5) through the full lens model: once on every
marker of the layout (scope "target") and once on the pose marker alone.

The first line runs Debian's Python, /usr/bin/python3, for which Debian's
python3-opencv is installed (a python3 earlier on PATH, e.g. a pyenv or
venv one, may not have cv2): the sweep file's command is the script itself.

--distance-bias-m B moves every pose B metres farther along its line of
sight (t scaled by (|t| + B) / |t|; default 0): a deliberately biased build,
to show a regression gate catch it.
"""

import argparse
import json
import sys
import time

import cv2
import numpy as np

PROTOCOL = "rig-estimator"
VERSION = 1
NAME = "opencv_solvepnp"
ESTIMATOR_VERSION = "1.0 (OpenCV " + cv2.__version__ + ")"


def send(message):
    sys.stdout.write(json.dumps(message) + "\n")
    sys.stdout.flush()


def solve(object_points, image_points, camera):
    """The pose from >= 4 coplanar correspondences, or None."""
    K = np.array(camera["K"], dtype=np.float64)
    dist = np.array(camera["distortion"], dtype=np.float64)
    ok, rvec, tvec = cv2.solvePnP(
        np.array(object_points, dtype=np.float64),
        np.array(image_points, dtype=np.float64),
        K, dist, flags=cv2.SOLVEPNP_IPPE)
    if not ok:
        return None
    R, _ = cv2.Rodrigues(rvec)
    return R, tvec.reshape(3)


def estimate(frame, bias_m):
    image = cv2.imread(frame["image"]["path"], cv2.IMREAD_UNCHANGED)
    if image is None:
        raise ValueError("cannot read " + frame["image"]["path"])
    camera = frame["camera"]
    if image.shape[1] != camera["width_px"] or image.shape[0] != camera["height_px"]:
        raise ValueError("image is %dx%d px, calibration %dx%d px" % (
            image.shape[1], image.shape[0], camera["width_px"], camera["height_px"]))
    layout = {m["id"]: m["corners_m"] for m in frame["target"]["markers"]}
    seen = [d for d in frame.get("detections", []) if d["marker_id"] in layout]
    scopes = [("target", seen)]
    pose_marker = frame["target"]["pose_marker"]
    scopes += [(pose_marker, [d for d in seen if d["marker_id"] == pose_marker])]
    poses = []
    for scope, markers in scopes:
        if not markers:
            continue
        object_points = [p for d in markers for p in layout[d["marker_id"]]]
        image_points = [p for d in markers for p in d["corners_px"]]
        pose = solve(object_points, image_points, camera)
        if pose is None:
            continue
        R, t = pose
        t = t * (1 + bias_m / np.linalg.norm(t))
        poses.append({"scope": scope, "R": R.tolist(), "t_m": t.tolist()})
    return poses


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--distance-bias-m", type=float, default=0.0,
                        help="add this to every distance, metres (default 0)")
    args = parser.parse_args()
    for line in sys.stdin:
        message = json.loads(line)
        if message["type"] == "hello":
            send({"type": "hello", "protocol": PROTOCOL, "version": VERSION,
                  "name": NAME, "estimator_version": ESTIMATOR_VERSION})
            if message.get("protocol") != PROTOCOL or message.get("version") != VERSION:
                return 2
            continue
        start = time.perf_counter()
        try:
            poses = estimate(message, args.distance_bias_m)
        except (ValueError, KeyError, cv2.error) as e:
            send({"type": "error", "frame_id": message["frame_id"], "message": str(e)})
            continue
        send({"type": "result", "frame_id": message["frame_id"], "poses": poses,
              "time_us": (time.perf_counter() - start) * 1e6})
    return 0


if __name__ == "__main__":
    sys.exit(main())
