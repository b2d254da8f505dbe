#include "rt/ray.h"

#include <utility>

namespace cuberille::rt {

WatertightRay::WatertightRay(const Ray& ray) : origin(ray.origin) {
    const glm::vec3 d = glm::abs(ray.direction);
    kz = d.x >= d.y && d.x >= d.z ? 0 : (d.y >= d.z ? 1 : 2);
    kx = (kz + 1) % 3;
    ky = (kx + 1) % 3;
    if (ray.direction[kz] < 0.0f) std::swap(kx, ky);  // keep the winding's sign
    shearX = ray.direction[kx] / ray.direction[kz];
    shearY = ray.direction[ky] / ray.direction[kz];
    shearZ = 1.0f / ray.direction[kz];
}

bool WatertightRay::intersect(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, float tMin,
                              float tMax, RayHit* hit) const {
    const glm::vec3 A = a - origin, B = b - origin, C = c - origin;
    const float ax = A[kx] - shearX * A[kz], ay = A[ky] - shearY * A[kz];
    const float bx = B[kx] - shearX * B[kz], by = B[ky] - shearY * B[kz];
    const float cx = C[kx] - shearX * C[kz], cy = C[ky] - shearY * C[kz];
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    // Exactly zero in float may be a rounded sign: decide edge hits in double, where the products
    // of two floats are exact (section 3.3 of the paper).
    if (u == 0.0f || v == 0.0f || w == 0.0f) {
        u = float(double(cx) * double(by) - double(cy) * double(bx));
        v = float(double(ax) * double(cy) - double(ay) * double(cx));
        w = float(double(bx) * double(ay) - double(by) * double(ax));
    }
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
    const float det = u + v + w;
    if (det == 0.0f) return false;
    const float az = shearZ * A[kz], bz = shearZ * B[kz], cz = shearZ * C[kz];
    const float t = (u * az + v * bz + w * cz) / det;
    if (!(t >= tMin && t <= tMax)) return false;
    hit->t = t;
    hit->u = v / det;
    hit->v = w / det;
    return true;
}

}  // namespace cuberille::rt
