#include "raster/sheen_lobe.h"

#include <vector>

#include <tbb/parallel_for.h>

namespace cuberille::raster {
namespace {

// Quadrature steps for the table's entries (sheenAlbedoIntegral says how close they come).
constexpr int kTableSteps = 16;

}  // namespace

double sheenAlbedoIntegral(double nDotV, double roughness, int steps) {
    // Over n.l = s² with s uniform: the lobe of a smooth sheen seen at a grazing view is a thin
    // band just above the horizon, and uniform steps in s are fine there (dl = 2 s ds dphi).
    const double alpha = roughness * roughness;
    const double vx = std::sqrt(std::max(0.0, 1.0 - nDotV * nDotV)), vz = nDotV;
    const int phiSteps = 2 * steps;
    const double ds = 1.0 / steps, dPhi = M_PI / phiSteps;
    double sum = 0.0;
    for (int t = 0; t < steps; ++t) {
        const double s = (t + 0.5) * ds, lz = s * s, sinT = std::sqrt(1.0 - lz * lz);
        for (int p = 0; p < phiSteps; ++p) {
            const double phi = (p + 0.5) * dPhi;
            const double lx = sinT * std::cos(phi), ly = sinT * std::sin(phi);
            const double hx = lx + vx, hy = ly, hz = lz + vz;
            const double h2 = hx * hx + hy * hy + hz * hz;
            const double nDotH2 = h2 > 0.0 ? hz * hz / h2 : 0.0;
            const double d = (2.0 + 1.0 / alpha) * std::pow(std::max(1.0 - nDotH2, 0.0), 0.5 / alpha) / (2.0 * M_PI);
            const double v = 0.25 / (lz + vz - lz * vz);
            sum += d * v * lz * 2.0 * s;
        }
    }
    return 2.0 * sum * ds * dPhi;  // x 2: the other half circle in phi
}

const float* sheenAlbedoTable() {
    static const std::vector<float> table = [] {
        std::vector<float> t(size_t(kSheenAlbedoColumns * kSheenAlbedoRows));
        tbb::parallel_for(0, kSheenAlbedoRows, [&](int j) {  // 30 ms on one core; each entry on its own
            const double roughness =
                kSheenRoughnessFloor + (1.0 - kSheenRoughnessFloor) * double(j) / (kSheenAlbedoRows - 1);
            for (int i = 0; i < kSheenAlbedoColumns; ++i) {
                const double s = double(i) / (kSheenAlbedoColumns - 1);
                t[size_t(j * kSheenAlbedoColumns + i)] = float(sheenAlbedoIntegral(std::max(1e-4, s * s), roughness, kTableSteps));
            }
        });
        return t;
    }();
    return table.data();
}

}  // namespace cuberille::raster
