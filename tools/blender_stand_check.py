# Imports a stand export of `sylva export` into Blender and measures what a user sees.
#
#   blender -b --factory-startup --python tools/blender_stand_check.py -- STAND.glb OUT.json \
#       [--half M] [--px N] [--png TOP.png]
#
# Writes OUT.json with
#   mesh_objects     visible mesh objects after the import
#   tree_objects     visible mesh objects under the node "trees" (one per tree expected)
#   ground_objects   visible mesh objects under the node "ground" (terrain, obstacles)
#   sapling_objects  visible mesh objects under the node "saplings" (the regeneration layer)
#   trees            tree nodes (children of "trees")
#   cover            share (0-1) of the pixels of a top-down orthographic render of the square
#                    of half side M metres (default 10) around the scene's origin (the export
#                    area's centre) that the trees cover: Cycles, transparent film, the ground
#                    hidden, alpha >= 0.5 counted as covered
#   half_m, px       the square and the render's size
# Blender 3.4 (Debian's package) with its numpy 1.24: the glTF importer needs `np.bool`.
import json
import sys

import bpy
import numpy as np

if not hasattr(np, "bool"):
    np.bool = bool  # the glTF importer of Blender 3.4 still uses the alias numpy 1.24 removed

argv = sys.argv[sys.argv.index("--") + 1:]
glb, out = argv[0], argv[1]
opts = dict(zip(argv[2::2], argv[3::2]))
half = float(opts.get("--half", "10"))
px = int(opts.get("--px", "200"))
png = opts.get("--png")

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)


def under(obj, name):
    p = obj.parent
    while p is not None:
        if p.name.split(".")[0] == name:
            return True
        p = p.parent
    return False


meshes = [o for o in bpy.context.scene.objects if o.type == "MESH" and o.visible_get()]
trees_root = [o for o in bpy.context.scene.objects if o.name.split(".")[0] == "trees"]
result = {
    "mesh_objects": len(meshes),
    "tree_objects": sum(1 for o in meshes if under(o, "trees")),
    "ground_objects": sum(1 for o in meshes if under(o, "ground")),
    "sapling_objects": sum(1 for o in meshes if under(o, "saplings")),
    "trees": len(trees_root[0].children) if trees_root else 0,
    "half_m": half,
    "px": px,
}

# top-down orthographic render of the trees alone
for o in meshes:
    if under(o, "ground") or under(o, "saplings"):
        o.hide_render = True
scene = bpy.context.scene
cam_data = bpy.data.cameras.new("top")
cam_data.type = "ORTHO"
cam_data.ortho_scale = 2.0 * half
cam = bpy.data.objects.new("top", cam_data)
scene.collection.objects.link(cam)
# glTF y up becomes Blender z up: the scene's origin is at (0, 0, 0), the trees above it
cam.location = (0.0, 0.0, 500.0)
cam.rotation_euler = (0.0, 0.0, 0.0)
cam_data.clip_end = 2000.0
scene.camera = cam
scene.render.engine = "CYCLES"
scene.cycles.samples = 4
scene.cycles.use_denoising = False
scene.cycles.max_bounces = 1
scene.cycles.transparent_max_bounces = 64
scene.render.film_transparent = True
scene.render.resolution_x = px
scene.render.resolution_y = px
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "PNG"
scene.render.image_settings.color_mode = "RGBA"
path = png or (out + ".png")
scene.render.filepath = path
bpy.ops.render.render(write_still=True)
img = bpy.data.images.load(path)
a = np.array(img.pixels[:], dtype=np.float32).reshape(-1, 4)[:, 3]
result["cover"] = float((a >= 0.5).mean())
with open(out, "w") as f:
    json.dump(result, f)
print("SYLVA_STAND_CHECK", json.dumps(result))
