#pragma once
// Built-in scenes generated in code, so demos, tests and benchmarks need no files.
//
//   demo      the default scene: a generated checker texture, metallic-roughness spheres,
//             Lambert tori, a blended glass sphere, an alpha-masked screen, sun + point light
//   field     about 1M triangles: a 12x12 field of spheres and tori on a ground plane, one
//             directional light, Lambert shading
//   subpixel  about 10M triangles, most smaller than a pixel at 1920x1080: a finely
//             tessellated rolling terrain filling the view
//   fill      a few hundred large overlapping triangles (fill-bound)

#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "scene/mesh.h"
#include "scene/scene.h"

namespace cuberille::scene {

const std::vector<std::string>& proceduralSceneNames();
bool isProceduralScene(const std::string& name);
/// `detail` scales tessellation (1 = the documented triangle counts).
Scene makeProceduralScene(const std::string& name, float detail = 1.0f);

// Building blocks, also used by tests.
Mesh makeSphere(glm::vec3 centre, float radius, int rings, int segments);
Mesh makeTorus(glm::vec3 centre, float majorRadius, float minorRadius, int rings, int segments);
Mesh makeGround(float halfExtent, float height);

/// A texture made in code: a two-tone checkerboard (linear RGB), size x size texels, `cells`
/// squares a side.
std::shared_ptr<const raster::Texture> checkerTexture(int size, int cells, glm::vec3 a, glm::vec3 b);

}  // namespace cuberille::scene
