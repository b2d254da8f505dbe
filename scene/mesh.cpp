#include "scene/mesh.h"

#include <cmath>

#include "raster/huge_pages.h"

namespace cuberille::scene {

void computeVertexNormals(Mesh& mesh) {
    std::vector<glm::dvec3> sum;
    raster::resizeAdvised(sum, mesh.positions.size(), glm::dvec3(0.0));
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
        const glm::dvec3 n = glm::cross(glm::dvec3(mesh.positions[b] - mesh.positions[a]),
                                        glm::dvec3(mesh.positions[c] - mesh.positions[a]));
        sum[a] += n, sum[b] += n, sum[c] += n;
    }
    raster::resizeAdvised(mesh.normals, mesh.positions.size());
    for (size_t i = 0; i < sum.size(); ++i) {
        const double len = glm::length(sum[i]);
        mesh.normals[i] = len > 0.0 ? glm::vec3(sum[i] / len) : glm::vec3(0.0f, 0.0f, 1.0f);
    }
}

// Lengyel's per-triangle tangent basis, summed per vertex. glTF's texture v runs down the
// image while a normal map's green channel points up, so the bitangent the map means is
// -dP/dv; the handedness w says whether cross(n, t) points that way.
void computeVertexTangents(Mesh& mesh) {
    const size_t n = mesh.positions.size();
    std::vector<glm::dvec3> dPdu(n, glm::dvec3(0.0)), dPdv(n, glm::dvec3(0.0));
    if (mesh.texCoords.size() == n) {
        for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
            const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
            const glm::dvec3 e1(mesh.positions[b] - mesh.positions[a]), e2(mesh.positions[c] - mesh.positions[a]);
            const glm::dvec2 d1(mesh.texCoords[b] - mesh.texCoords[a]), d2(mesh.texCoords[c] - mesh.texCoords[a]);
            const double det = d1.x * d2.y - d2.x * d1.y;
            if (!(std::abs(det) > 1e-20)) continue;
            const glm::dvec3 u = (e1 * d2.y - e2 * d1.y) / det, v = (e2 * d1.x - e1 * d2.x) / det;
            for (uint32_t i : {a, b, c}) dPdu[i] += u, dPdv[i] += v;
        }
    }
    mesh.tangents.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const glm::dvec3 normal = i < mesh.normals.size() ? glm::dvec3(mesh.normals[i]) : glm::dvec3(0, 0, 1);
        glm::dvec3 t = dPdu[i] - normal * glm::dot(normal, dPdu[i]);
        if (!(glm::length(t) > 1e-12)) {  // no usable UVs: any perpendicular
            t = glm::cross(normal, std::abs(normal.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0));
            if (!(glm::length(t) > 1e-12)) t = glm::dvec3(1, 0, 0);
        }
        t = glm::normalize(t);
        const double w = glm::dot(glm::cross(normal, t), -dPdv[i]) < 0.0 ? -1.0 : 1.0;
        mesh.tangents[i] = glm::vec4(glm::vec3(t), float(w));
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
