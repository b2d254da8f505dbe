#pragma once
// glTF 2.0 (`.gltf`, `.glb`) through tinygltf: the default scene's node hierarchy (TRS or
// matrix; mirrored transforms flip the winding back), posed by the first animation at a time,
// every mesh primitive of mode TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN (POINTS and LINES are
// skipped with one warning), indexed or not, with POSITION, NORMAL (computed when absent),
// TANGENT (computed when a normal map needs it), COLOR_0 (RGB or RGBA, float or normalised
// integers) and one TEXCOORD set.
// Materials: metallic-roughness factors and the five texture slots (base colour, metallic-
// roughness, normal, occlusion, emissive) with their samplers' wrap modes and filters and
// KHR_texture_transform; alphaMode and alphaCutoff; doubleSided; KHR_materials_unlit.
// Cameras (perspective and orthographic) and KHR_lights_punctual lights (directional, point,
// spot) come from the nodes that carry them. Skins and morph targets (POSITION and NORMAL
// deltas; weights animated, per node or per mesh) deform the meshes on the CPU at load.
// Sparse accessors, quantized attributes (KHR_mesh_quantization),
// KHR_materials_emissive_strength and WebP textures (EXT_texture_webp, through libwebp) are read. A file whose extensionsRequired names another
// extension is refused (InputError naming them); other extensions merely used, and texture
// slots on a second TEXCOORD set, each warn once, naming it.
//
// What we do with tinygltf's answer is checked: every accessor's range against its buffer
// view and buffer, every index against the vertex count, the node depth (at most 256) and
// cycles, before anything is read. Failures throw InputError naming the file, the place
// (mesh, primitive, accessor, node) and the problem.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "raster/draw.h"
#include "scene/camera.h"
#include "scene/input_error.h"
#include "scene/load_stats.h"
#include "scene/mesh.h"

namespace cuberille::scene {

struct GltfScene {
    std::vector<Mesh> meshes;
    std::vector<Camera> cameras;  // the scene's camera nodes, in traversal order
    std::vector<raster::Light> lights;  // KHR_lights_punctual, in node order
    LoadStats stats;
};

/// A glTF file parsed once and posed as often as asked: a renderer that draws several times or
/// several frames of an animation reads and checks the file once and decodes each texture once.
/// Not safe to pose from two threads at once (the texture cache is filled as poses need it).
class GltfDocument {
public:
    /// Reads and parses the file; throws InputError for an unreadable or malformed container.
    GltfDocument(const std::filesystem::path& path, const WarningSink& warn);
    GltfDocument(GltfDocument&&) noexcept;
    ~GltfDocument();

    /// The default scene posed as loadGltf describes. A warning already given by an earlier
    /// pose of this document is not repeated.
    GltfScene pose(float timeSeconds, const std::string& animation, const WarningSink& warn) const;

    /// The file's animations' names in file order ("" for an unnamed one).
    std::vector<std::string> animationNames() const;

private:
    struct Parsed;
    std::unique_ptr<Parsed> parsed_;
};

/// timeSeconds poses an animation's node channels (translation, rotation, scale, morph weights)
/// at that time, clamped to the clip's range. `animation` chooses which: its name, or its index
/// in the file as a decimal number; empty, the first. A name or index the file lacks is an
/// InputError naming the file's animations.
GltfScene loadGltf(const std::filesystem::path& path, const WarningSink& warn, float timeSeconds = 0.0f,
                   const std::string& animation = "");

}  // namespace cuberille::scene
