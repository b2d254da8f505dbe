#pragma once
// glTF 2.0 (`.gltf`, `.glb`) through tinygltf: the default scene's node hierarchy (TRS or
// matrix; mirrored transforms flip the winding back), posed by the first animation at a time,
// every mesh primitive of mode TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN (POINTS and LINES are
// skipped with one warning), indexed or not, with POSITION, NORMAL (computed when absent),
// COLOR_0 (float or normalised integers), the material's baseColorFactor, alphaMode and
// alphaCutoff, baseColorTexture
// (with its sampler's wrap modes; trilinear filtering) and doubleSided flag. Cameras
// (perspective and orthographic) come from the nodes that carry them. Skins and morph targets
// (POSITION and NORMAL deltas; weights animated, per node or per mesh) deform the meshes on the
// CPU at load.
// KHR_lights_punctual directional lights are collected (the renderer uses the first);
// KHR_materials_unlit materials are drawn without lighting.
// Not yet (issue 3): other texture slots, KHR_texture_transform, point and spot
// lights, other extensions; a file that uses them loads with a warning naming what was ignored.
//
// What we do with tinygltf's answer is checked: every accessor's range against its buffer
// view and buffer, every index against the vertex count, the node depth (at most 256) and
// cycles, before anything is read. Failures throw InputError naming the file, the place
// (mesh, primitive, accessor, node) and the problem.

#include <filesystem>
#include <vector>

#include "raster/draw.h"
#include "scene/camera.h"
#include "scene/input_error.h"
#include "scene/mesh.h"

namespace cuberille::scene {

struct GltfScene {
    std::vector<Mesh> meshes;
    std::vector<Camera> cameras;  // the scene's camera nodes, in traversal order
    std::vector<raster::DirectionalLight> directionalLights;  // KHR_lights_punctual, node order
};

/// timeSeconds poses the first animation's node channels (translation, rotation, scale) at that
/// time, clamped to the clip's range.
GltfScene loadGltf(const std::filesystem::path& path, const WarningSink& warn, float timeSeconds = 0.0f);

}  // namespace cuberille::scene
