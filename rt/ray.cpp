#include "rt/ray.h"

#include <utility>

namespace cuberille::rt {

WatertightRay::WatertightRay(const Ray& ray) : origin(ray.origin), box(ray) {
    const glm::vec3 d = glm::abs(ray.direction);
    kz = d.x >= d.y && d.x >= d.z ? 0 : (d.y >= d.z ? 1 : 2);
    kx = (kz + 1) % 3;
    ky = (kx + 1) % 3;
    if (ray.direction[kz] < 0.0f) std::swap(kx, ky);  // keep the winding's sign
    shearX = ray.direction[kx] / ray.direction[kz];
    shearY = ray.direction[ky] / ray.direction[kz];
    shearZ = 1.0f / ray.direction[kz];
}

void WatertightRay::edgeWeightsInDouble(float ax, float ay, float bx, float by, float cx, float cy, float& u, float& v,
                                        float& w) {
    u = float(double(cx) * double(by) - double(cy) * double(bx));
    v = float(double(ax) * double(cy) - double(ay) * double(cx));
    w = float(double(bx) * double(ay) - double(by) * double(ax));
}

}  // namespace cuberille::rt
