#include "scene/mesh.h"

#include <cmath>

namespace cuberille::scene {

void computeVertexNormals(Mesh& mesh) {
    std::vector<glm::dvec3> sum(mesh.positions.size(), glm::dvec3(0.0));
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
        const glm::dvec3 n = glm::cross(glm::dvec3(mesh.positions[b] - mesh.positions[a]),
                                        glm::dvec3(mesh.positions[c] - mesh.positions[a]));
        sum[a] += n, sum[b] += n, sum[c] += n;
    }
    mesh.normals.resize(mesh.positions.size());
    for (size_t i = 0; i < sum.size(); ++i) {
        const double len = glm::length(sum[i]);
        mesh.normals[i] = len > 0.0 ? glm::vec3(sum[i] / len) : glm::vec3(0.0f, 0.0f, 1.0f);
    }
}

Bounds boundsOf(const Mesh& mesh) {
    Bounds b;
    for (const glm::vec3& p : mesh.positions) b.extend(p);
    return b;
}

Bounds boundsOf(const std::vector<Mesh>& meshes) {
    Bounds b;
    for (const Mesh& m : meshes) {
        const Bounds mb = boundsOf(m);
        if (!mb.empty()) b.extend(mb.min), b.extend(mb.max);
    }
    return b;
}

float srgbToLinear(float e) {
    return e <= 0.04045f ? e / 12.92f : std::pow((e + 0.055f) / 1.055f, 2.4f);
}

}  // namespace cuberille::scene
