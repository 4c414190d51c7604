# bench_cycles.py -- Blender's Cycles renders a benchmark scene with the
# settings of the project's path tracer, for the equal-time comparison of
# make bench-cycles (tests/bench_cycles.sh, tests/bench_equal_time.c).
#
#   blender -b --factory-startup -P tests/bench_cycles.py -- \
#       --scene build/bench/scenes/cornell-10k.scene --spp 64 --width 128 --threads 2 \
#       --seed 1 --out build/bench/cycles/cornell-10k-64-1.exr --manifest build/bench/runs.csv
#
# The scene file (written by bench_scenes --write) gives the camera and the
# OBJ file; the OBJ's MTL gives the materials, read here by the rules the
# project's loader follows (docs/scene-format.md, chapter 09): Ke > 0 an
# emitter from its front face (Kd its albedo), illum 4/6/7/9 or d < 1 smooth
# glass of index Ni, Pm >= 0.5 GGX metal (F0 = Kd, alpha = Pr^2), Ks
# larger than Kd GGX metal (F0 = Ks, alpha = sqrt(2 / (Ns + 2))), illum 3
# without Pm a metal as Blender writes one (F0 = Kd, alpha = r^2 where
# Ns = 1000 (1 - r)^2), else Lambertian Kd. Matched settings: CPU device,
# no denoiser, no adaptive sampling, no clamping, no glossy filter, no
# light threshold, a 1-pixel box filter, the scene's uniform world (black
# unless it has a background line), the same eye, target and vertical
# field of view, --max-bounces on every kind of bounce, a fixed seed. Cycles keeps what makes it Cycles: its sampler, its Russian
# roulette, its light sampling.
#
# Appends 'cycles,SCENE,SPP,THREADS,SEED,CPU_S,WALL_S,OUT' to --manifest:
# the CPU time of this process (all its threads) and the wall time of the
# render call alone (scene synchronisation, BVH build and sampling; not
# Blender's start-up or the import).
import argparse
import math
import os
import shlex
import sys
import time

import bpy
from mathutils import Vector


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="bench_cycles.py")
    p.add_argument("--scene", required=True, help="a scene file of bench_scenes --write")
    p.add_argument("--out", required=True, help="the EXR to write")
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--width", type=int, default=128)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--max-bounces", type=int, default=64, help="the project's max_depth (default 64)")
    p.add_argument("--manifest", help="append one line per render here")
    return p.parse_args(argv)


def read_scene(path):
    """The camera (eye, target, up, fov), the OBJ path and the background of a scene file."""
    camera, obj, background = None, None, (0.0, 0.0, 0.0)
    with open(path) as f:
        for number, line in enumerate(f, 1):
            words = shlex.split(line.split("#", 1)[0])
            if not words:
                continue
            if words[0] == "camera":
                keys = {}
                i = 1
                while i < len(words):
                    n = 1 if words[i] == "fov" else 3
                    keys[words[i]] = [float(w) for w in words[i + 1:i + 1 + n]]
                    i += 1 + n
                camera = (keys["eye"], keys["target"], keys.get("up", [0, 1, 0]), keys.get("fov", [40])[0])
            elif words[0] == "mesh":
                obj = os.path.join(os.path.dirname(path), words[words.index("path") + 1])
            elif words[0] == "background":
                background = tuple(float(w) for w in words[1:4])
            else:
                sys.exit("%s:%d: bench_cycles.py reads only camera, mesh and background lines" % (path, number))
    if camera is None or obj is None:
        sys.exit("%s: needs a camera and a mesh line" % path)
    return camera, obj, background


def read_mtl(path):
    """name -> dict of the MTL statements the project's loader reads."""
    materials, current = {}, None
    with open(path) as f:
        for line in f:
            words = line.split("#", 1)[0].split()
            if not words:
                continue
            if words[0] == "newmtl":
                current = materials.setdefault(words[1], {"Kd": (0.8, 0.8, 0.8), "Ks": (0, 0, 0), "Ke": (0, 0, 0),
                                                          "Ns": 0.0, "Ni": 1.0, "d": 1.0, "illum": -1,
                                                          "Pm": -1.0, "Pr": -1.0})
            elif current is not None and words[0] in ("Kd", "Ks", "Ke"):
                current[words[0]] = tuple(float(w) for w in words[1:4])
            elif current is not None and words[0] in ("Ns", "Ni", "d", "Pm", "Pr"):
                current[words[0]] = float(words[1])
            elif current is not None and words[0] == "Tr":
                current["d"] = 1.0 - float(words[1])
            elif current is not None and words[0] == "illum":
                current["illum"] = int(words[1])
    return materials


def to_blender(p):
    """OBJ's +Y up to Blender's +Z up, as the importer maps it (forward -Z, up Y)."""
    return Vector((p[0], -p[2], p[1]))


def metal_of(m):
    """(F0, alpha) of a GGX metal, as chapter 09's pt_material_from_mtl decides, or None."""
    phong = min(1.0, max(0.001, math.sqrt(2.0 / (max(m["Ns"], 0.0) + 2.0))))
    if m["Pm"] >= 0.5:
        return m["Kd"], max(0.001, m["Pr"] ** 2) if m["Pr"] >= 0.0 else phong
    if max(m["Ks"]) > max(m["Kd"]):
        return m["Ks"], phong
    if m["Pm"] < 0.0 and m["illum"] == 3:
        r = 1.0 - math.sqrt(min(1.0, max(m["Ns"], 0.0) / 1000.0))
        return m["Kd"], min(1.0, max(0.001, r * r))
    return None


def build_material(mat, m):
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    rgba = lambda c: (c[0], c[1], c[2], 1.0)
    emits = max(m["Ke"]) > 0.0
    transparent = m["illum"] in (4, 6, 7, 9) or m["d"] < 1.0
    if emits:
        # L_e from the front face only, and the albedo's diffuse reflection
        diffuse = nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = rgba(m["Kd"])
        front = nodes.new("ShaderNodeEmission")
        front.inputs["Color"].default_value = rgba(m["Ke"])
        front.inputs["Strength"].default_value = 1.0
        back = nodes.new("ShaderNodeEmission")
        back.inputs["Strength"].default_value = 0.0
        geometry = nodes.new("ShaderNodeNewGeometry")
        side = nodes.new("ShaderNodeMixShader")
        links.new(geometry.outputs["Backfacing"], side.inputs["Fac"])
        links.new(front.outputs["Emission"], side.inputs[1])
        links.new(back.outputs["Emission"], side.inputs[2])
        add = nodes.new("ShaderNodeAddShader")
        links.new(diffuse.outputs["BSDF"], add.inputs[0])
        links.new(side.outputs["Shader"], add.inputs[1])
        links.new(add.outputs["Shader"], out.inputs["Surface"])
    elif transparent:
        glass = nodes.new("ShaderNodeBsdfGlass")
        glass.distribution = "SHARP"
        glass.inputs["Color"].default_value = (1, 1, 1, 1)
        glass.inputs["IOR"].default_value = m["Ni"] if m["Ni"] > 1.0 else 1.5
        links.new(glass.outputs["BSDF"], out.inputs["Surface"])
    elif metal_of(m) is not None:
        f0, alpha = metal_of(m)
        metal = nodes.new("ShaderNodeBsdfPrincipled")
        metal.distribution = "GGX"
        metal.inputs["Base Color"].default_value = rgba(f0)
        metal.inputs["Metallic"].default_value = 1.0
        metal.inputs["Roughness"].default_value = math.sqrt(alpha)  # Cycles' alpha is roughness^2
        metal.inputs["Specular"].default_value = 0.5
        links.new(metal.outputs["BSDF"], out.inputs["Surface"])
    else:
        diffuse = nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = rgba(m["Kd"])
        diffuse.inputs["Roughness"].default_value = 0.0
        links.new(diffuse.outputs["BSDF"], out.inputs["Surface"])


def set_up_scene(args, camera, obj_path, background):
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)
    bpy.ops.wm.obj_import(filepath=obj_path, forward_axis="NEGATIVE_Z", up_axis="Y")
    mtl = read_mtl(os.path.splitext(obj_path)[0] + ".mtl")
    for mat in bpy.data.materials:
        if mat.name in mtl:
            build_material(mat, mtl[mat.name])
    scene = bpy.context.scene
    eye, target, up, fov = camera
    cam_data = bpy.data.cameras.new("bench")
    cam_data.sensor_fit = "VERTICAL"
    cam_data.angle_y = math.radians(fov)
    cam_data.clip_start = 1e-3
    cam_data.clip_end = 1e7
    cam = bpy.data.objects.new("bench", cam_data)
    scene.collection.objects.link(cam)
    cam.location = to_blender(eye)
    direction = to_blender(target) - to_blender(eye)
    cam.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    scene.camera = cam
    world = scene.world or bpy.data.worlds.new("bench")
    scene.world = world
    world.use_nodes = False
    world.color = background  # the environment's radiance, uniform (black unless the scene says)

    r, c = scene.render, scene.cycles
    r.engine = "CYCLES"
    c.device = "CPU"
    c.samples = args.spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.light_sampling_threshold = 0.0
    for name in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
                 "transparent_max_bounces"):
        setattr(c, name, args.max_bounces)
    c.volume_bounces = 0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.seed = args.seed
    c.use_animated_seed = False
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    r.threads_mode = "FIXED"
    r.threads = args.threads
    r.resolution_x = r.resolution_y = args.width
    r.resolution_percentage = 100
    r.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    s = r.image_settings
    s.file_format = "OPEN_EXR"
    s.color_mode = "RGB"
    s.color_depth = "32"
    s.exr_codec = "ZIP"


def main():
    args = parse_args()
    camera, obj_path, background = read_scene(args.scene)
    set_up_scene(args, camera, obj_path, background)
    cpu0, wall0 = time.process_time(), time.perf_counter()
    bpy.ops.render.render()
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    temp = args.out + ".tmp.exr"
    bpy.data.images["Render Result"].save_render(temp)
    os.replace(temp, args.out)  # a reader sees no half-written image
    name = os.path.splitext(os.path.basename(args.scene))[0]
    line = "cycles,%s,%d,%d,%d,%.6f,%.6f,%s\n" % (name, args.spp, args.threads, args.seed, cpu, wall, args.out)
    print("bench_cycles.py: " + line.strip())
    if args.manifest:
        with open(args.manifest, "a") as f:
            f.write(line)


main()
