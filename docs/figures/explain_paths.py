#!/usr/bin/env python3
"""explain_paths.py -- the paths of chapter 09's picture, for the book's
clickable figure: runs the chapter's program with --explain on a grid of
pixels (one sample each) and writes what each path did, projected onto the
image, as JSON:

  {"width": W, "height": H, "image": "out/ch09.png", "command": "...",
   "paths": [{"pixel": [x, y], "value": [r, g, b],
              "segments": [{"kind": K, "from": [x, y], "to": [x, y]}, ...],
              "lights": [[x, y], ...],   (light samples without a shadow ray)
              "end": {"why": W, "at": [x, y]}}, ...]}

K is "camera" (the eye ray to its first hit), "bounce" (the next ray to
the next hit), "shadow" (a light sample's shadow ray, unblocked), "blocked"
(one that something stopped) or "escape" (a ray that left the scene, drawn
some way along); the end says why the path stopped ("roulette", "max
depth", "escape", "no effect"). Everything comes from the program's
--explain text and its camera line (common/program/program.c), so the drawing is
what the renderer did, not a re-computation.

  docs/figures/explain_paths.py PROGRAM GRID OUT.json [program flags...]

GRID pixels a side, at the centres of a GRID x GRID tiling of the image.
"""
import json
import os
import re
import subprocess
import sys

NUM = r"(-?[0-9.]+(?:e[-+]?[0-9]+)?|-?inf|nan)"
VEC = r"\(" + NUM + r", " + NUM + r", " + NUM + r"\)"


def vec(match, first):
    return [float(match.group(first + k)) for k in range(3)]


class Camera:
    def __init__(self, line, width, height):
        m = re.search(r"eye " + VEC + r", forward " + VEC + r", right " + VEC + r", up " + VEC +
                      r", half width " + NUM + r", half height " + NUM, line)
        if not m:
            raise SystemExit("explain_paths.py: no camera line in the program's --explain output")
        self.eye, self.forward, self.right, self.up = (vec(m, 1 + 3 * k) for k in range(4))
        self.half_width, self.half_height = float(m.group(13)), float(m.group(14))
        self.width, self.height = width, height

    def depth(self, p):
        return sum((p[k] - self.eye[k]) * self.forward[k] for k in range(3))

    def project(self, p):
        d = [p[k] - self.eye[k] for k in range(3)]
        z = max(sum(d[k] * self.forward[k] for k in range(3)), 1e-6)
        sx = sum(d[k] * self.right[k] for k in range(3)) / z
        sy = sum(d[k] * self.up[k] for k in range(3)) / z
        x = self.width / 2 * (1 + sx / self.half_width)
        y = self.height / 2 * (1 - sy / self.half_height)
        return [round(x, 2), round(y, 2)]

    def far_point(self, origin, direction, length):
        """origin + t direction, t at most length, kept in front of the eye."""
        t = length
        toward = sum(direction[k] * self.forward[k] for k in range(3))
        if toward < 0:
            t = min(t, 0.95 * (self.depth(origin) - 1.0) / -toward)
        return [origin[k] + max(t, 0.0) * direction[k] for k in range(3)]


def path_of(text, camera, scene_size):
    segments, lights, end = [], [], None
    origin = direction = point = sample = None
    kind = "camera"
    for line in text.splitlines():
        body = line.strip()
        if m := re.match(r"sample [0-9]+ of [0-9]+, at \(" + NUM + r", " + NUM + r"\) in the image", body):
            sample = [round(float(m.group(1)), 2), round(float(m.group(2)), 2)]
        elif m := re.match(r"camera ray: from " + VEC + r" towards " + VEC, body):
            origin, direction, kind = vec(m, 1), vec(m, 4), "camera"
        elif m := re.match(r"next ray: from " + VEC + r" towards " + VEC, body):
            origin, direction, kind = vec(m, 1), vec(m, 4), "bounce"
        elif (m := re.search(r"^hit .* point " + VEC, body)) and origin is not None:
            point = vec(m, 1)
            # The eye ray, seen end on, runs from the sample's position on the image.
            start = sample if kind == "camera" else camera.project(origin)
            segments.append({"kind": kind, "from": start, "to": camera.project(point)})
            origin = None
        elif body.startswith("left the scene") and origin is not None:
            far = camera.far_point(origin, direction, scene_size)
            segments.append({"kind": "escape", "from": camera.project(origin), "to": camera.project(far)})
            end = {"why": "escape", "at": camera.project(far)}
            origin = None
        elif m := re.match(r"light sample at x' = " + VEC + r": (.*)", body):
            x = vec(m, 1)
            what = m.group(4)
            if what.startswith("visible"):
                segments.append({"kind": "shadow", "from": camera.project(point), "to": camera.project(x)})
            elif what.startswith("shadow ray blocked"):
                segments.append({"kind": "blocked", "from": camera.project(point), "to": camera.project(x)})
            else:
                lights.append(camera.project(x))
        elif "the path ends" in body and body.startswith("Russian roulette"):
            end = {"why": "roulette", "at": camera.project(point)}
        elif body.startswith("max depth"):
            end = {"why": "max depth", "at": camera.project(point)}
        elif body.startswith("no ") and "the path ends here" in body:
            end = {"why": "no effect", "at": camera.project(point)}
    return segments, lights, end


def main():
    if len(sys.argv) < 4:
        raise SystemExit(__doc__)
    program, grid, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    flags = sys.argv[4:]
    # --explain writes no image, but the program checks where it would go.
    run_flags = flags + ["--out", os.path.splitext(out)[0] + ".exr"]
    probe = subprocess.run([program, "--explain", "0,0", "--spp", "1"] + run_flags, capture_output=True, text=True,
                           check=True).stdout
    size = re.search(r"how pixel \(0, 0\) of ([0-9]+)x([0-9]+)", probe)
    width, height = int(size.group(1)), int(size.group(2))
    camera = Camera(next(l for l in probe.splitlines() if l.startswith("camera:")), width, height)
    scene_size = 2.0 * max(abs(c) for c in camera.eye)
    paths = []
    for j in range(grid):
        for i in range(grid):
            x, y = (2 * i + 1) * width // (2 * grid), (2 * j + 1) * height // (2 * grid)
            text = subprocess.run([program, "--explain", f"{x},{y}", "--spp", "1"] + run_flags, capture_output=True,
                                  text=True, check=True).stdout
            segments, lights, end = path_of(text, camera, scene_size)
            value = re.search(r"pixel \([0-9]+, [0-9]+\) = " + VEC, text)
            paths.append({"pixel": [x, y], "value": vec(value, 1) if value else None, "segments": segments,
                          "lights": lights, "end": end})
    name = program.split("/")[-1]
    command = "build/bin/" + name + " --explain X,Y --spp 1" + "".join(" " + f for f in flags)
    with open(out + ".tmp", "w") as f:
        json.dump({"width": width, "height": height, "command": command, "grid": grid, "paths": paths}, f,
                  separators=(",", ":"))
    os.replace(out + ".tmp", out)


if __name__ == "__main__":
    main()
