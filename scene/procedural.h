#pragma once
// Built-in scenes generated in code, so demos, tests and benchmarks need no files.
//
//   demo      the default scene: the sphere/torus field below
//   field     about 1M triangles: a 12x12 field of spheres and tori on a ground plane, one
//             directional light, Lambert shading
//   subpixel  about 10M triangles, most smaller than a pixel at 1920x1080: a finely
//             tessellated rolling terrain filling the view
//   fill      a few hundred large overlapping triangles (fill-bound)

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "raster/pipeline.h"
#include "scene/camera.h"

namespace cuberille::scene {

struct Mesh {
    std::vector<glm::vec3> positions;  // world space
    std::vector<glm::vec3> normals;
    std::vector<uint32_t> indices;
    glm::vec3 color{0.8f};  // linear albedo

    size_t triangleCount() const { return indices.size() / 3; }
};

struct ProceduralScene {
    std::string name;
    std::vector<Mesh> meshes;
    Camera camera;
    raster::DirectionalLight light;
    glm::vec4 background{0.0f, 0.0f, 0.0f, 1.0f};

    size_t triangleCount() const;
    /// Submits every mesh as one Lambert draw, depth-tested, back faces culled.
    void draw(raster::Pipeline& pipeline, float aspect) const;
};

const std::vector<std::string>& proceduralSceneNames();
bool isProceduralScene(const std::string& name);
/// `detail` scales tessellation (1 = the documented triangle counts).
ProceduralScene makeProceduralScene(const std::string& name, float detail = 1.0f);

// Building blocks, also used by tests.
Mesh makeSphere(glm::vec3 centre, float radius, int rings, int segments);
Mesh makeTorus(glm::vec3 centre, float majorRadius, float minorRadius, int rings, int segments);
Mesh makeGround(float halfExtent, float height);

}  // namespace cuberille::scene
