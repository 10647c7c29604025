#!/usr/bin/env python3
"""A scripted external estimator for rig's tests: protocol rig-estimator 1
done right, or one chosen way wrong.

  scripted_estimator.py MODE [--once FILE] [--at N]

MODE: ok (answers every frame at once with a fixed pose 1 m in front of the
camera), crash (exits with status 3 at frame N), segfault (kills itself with
SIGSEGV at frame N), hang (stops answering at frame N), malformed (answers
frame N with a line that is not JSON), bad_rotation (answers frame N with a
matrix that is not a rotation), wrong_version (says version 99 in the
handshake), silent_start (never answers the handshake), decline (answers frame
N with an error), no_pose (answers with zero poses).
--once FILE: misbehave only while FILE does not exist, creating it first (so
that the restarted process behaves). --at N: the frame (counted from 0 within
the process) at which to misbehave (default 0).
"""

import json
import os
import signal
import subprocess
import sys
import time


def send(message):
    sys.stdout.write(json.dumps(message) + "\n")
    sys.stdout.flush()


def main():
    mode = sys.argv[1]
    once = sys.argv[sys.argv.index("--once") + 1] if "--once" in sys.argv else None
    at = int(sys.argv[sys.argv.index("--at") + 1]) if "--at" in sys.argv else 0
    pid_file = sys.argv[sys.argv.index("--pid") + 1] if "--pid" in sys.argv else None
    if once is not None:
        if os.path.exists(once):
            mode = "ok"
        else:
            open(once, "w").close()
    frames = 0
    for line in sys.stdin:
        message = json.loads(line)
        if message["type"] == "hello":
            if mode == "silent_start":
                time.sleep(3600)
            send({"type": "hello", "protocol": "rig-estimator",
                  "version": 99 if mode == "wrong_version" else 1,
                  "name": "scripted-" + mode, "estimator_version": "0.1"})
            continue
        frame_id = message["frame_id"]
        here = frames == at
        frames += 1
        if here and mode == "crash":
            sys.exit(3)
        if here and mode == "segfault":
            os.kill(os.getpid(), signal.SIGSEGV)
        if here and mode == "hang":
            time.sleep(3600)
        if here and mode == "orphan":
            child = subprocess.Popen(["sleep", "3600"])
            with open(pid_file, "w") as f:
                f.write(str(child.pid))
            time.sleep(3600)
        if here and mode == "malformed":
            sys.stdout.write("this is not json\n")
            sys.stdout.flush()
            continue
        if here and mode == "decline":
            send({"type": "error", "frame_id": frame_id, "message": "no markers I trust"})
            continue
        R = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
        if here and mode == "bad_rotation":
            R = [[2, 0, 0], [0, 1, 0], [0, 0, 1]]
        poses = [] if mode == "no_pose" else [{"scope": "target", "R": R, "t_m": [0, 0, 1.0]}]
        if mode == "echo_detections":
            poses = [{"scope": d["marker_id"], "R": R, "t_m": [0, 0, 1.0]}
                     for d in message.get("detections", [])]
        send({"type": "result", "frame_id": frame_id, "poses": poses, "time_us": 5})
    return 0


if __name__ == "__main__":
    sys.exit(main())
