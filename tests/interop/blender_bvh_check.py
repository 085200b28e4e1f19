#!/usr/bin/env python3
"""Blender (pip `bpy`, installed by `scripts/install-deps.sh --with-blender` into .cache/bpy)
imports spacetime-cli's BVH with its default settings into its default scene, and the action
must last the clip: as many scene frames, at the scene's frame rate, as the clip has seconds
times that rate, to the last whole frame (Blender's importer makes one scene frame of each BVH frame; a 1000 Hz BVH once
became a 50 s action).

usage: blender_bvh_check.py SPACETIME_CLI SCENE.json WORKDIR BPY_PACKAGES"""
import json
import os
import site
import subprocess
import sys

cli, scene_path, work, packages = sys.argv[1:5]
site.addsitedir(packages)
try:
    import bpy
except ImportError as e:
    sys.exit(f"FAIL: bpy is not installed in {packages} (scripts/install-deps.sh --with-blender): {e}")

os.makedirs(work, exist_ok=True)
out = os.path.join(work, "out")
subprocess.run([cli, "solve", scene_path, "--out", out, "--quiet"], check=True, stdout=subprocess.DEVNULL)
scene = json.load(open(scene_path))
character = scene["characters"][0]["id"]
clip = scene["time"]["end"] - scene["time"]["start"]
blender_fps = bpy.context.scene.render.fps / bpy.context.scene.render.fps_base
bpy.ops.import_anim.bvh(filepath=os.path.join(out, character + ".bvh"))  # default settings
armature = bpy.context.object
first, last = armature.animation_data.action.frame_range[:]
seconds = (last - first) / blender_fps
print(f"Blender {bpy.app.version_string}: the {clip:g} s clip imports as frames {first:g}-{last:g} "
      f"at {blender_fps:g} fps = {seconds:g} s")
# A clip that is not a whole number of frames ends on the last whole frame (1.2 s at 24 fps:
# 28 frame times, 1.1667 s).
if not (0 <= clip - seconds < 1 / blender_fps):
    sys.exit("FAIL: the imported action does not last the clip")
