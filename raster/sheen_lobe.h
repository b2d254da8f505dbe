#pragma once
// KHR_materials_sheen's lobe: the Charlie microfibre distribution (Estevez and Kulla 2017,
// "Production Friendly Microfacet Sheen BRDF") with Neubelt and Pettineo's visibility (the
// extension's simpler choice, a division instead of Charlie's fitted exponentials), and the
// lobe's directional albedo E(n.v, roughness), tabulated once, which dims the material under
// the sheen by 1 - max(sheen colour) E (the extension's albedo scaling, taken at the view
// direction only, as its implementation notes allow).

#include <algorithm>
#include <cmath>

namespace cuberille::raster {

/// The least sheen roughness shaded. alpha = roughness² makes D's exponent 0.5 / alpha: 102 at
/// 0.07, a lobe about 0.14 wide in n.h at the horizon, which the albedo table's quadrature
/// resolves (SheenLobe.AlbedoTableMatchesAFineIntegral measures it); rougher than any fabric a
/// glTF exporter writes below it, and the sheen of a smoother one is a sliver at the silhouette.
inline constexpr float kSheenRoughnessFloor = 0.07f;

/// D(h) = (2 + 1/alpha) sin(theta_h)^(1/alpha) / (2 pi), alpha = roughness².
inline float charlieDistribution(float alpha, float nDotH) {
    const float sin2 = std::max(1.0f - nDotH * nDotH, 0.0f);
    return (2.0f + 1.0f / alpha) * std::pow(sin2, 0.5f / alpha) * float(0.5 / M_PI);
}

/// V = 1 / (4 (n.l + n.v - n.l n.v)); both cosines positive where it is read.
inline float neubeltVisibility(float nDotL, float nDotV) { return 0.25f / (nDotL + nDotV - nDotL * nDotV); }

/// The directional albedo table: kSheenAlbedoColumns entries in n.v, at n.v = (i / (columns -
/// 1))² (E rises steeply at grazing views of a smooth sheen, where the squares crowd), by
/// kSheenAlbedoRows in roughness, evenly from the floor to 1, read bilinearly. Within 0.0035 of
/// the integral wherever E <= 1 (where it is clamped the error does not show), measured on a
/// 40 x 40 grid of (n.v, roughness); 48 rows, not 32 (0.013): the steep rows are the smooth ones.
inline constexpr int kSheenAlbedoColumns = 32, kSheenAlbedoRows = 48;

/// The table, row-major by roughness. Made on first use (a draw with sheen), each entry in
/// double on its own: the same bits at any thread count.
const float* sheenAlbedoTable();

/// E(n.v, roughness): the sheen lobe's directional albedo (colour 1), bilinear in the table.
inline float sheenAlbedo(const float* table, float nDotV, float roughness) {
    constexpr float kLastColumn = float(kSheenAlbedoColumns - 1), kLastRow = float(kSheenAlbedoRows - 1);
    const float fx = std::sqrt(std::clamp(nDotV, 0.0f, 1.0f)) * kLastColumn;
    const float fy = std::clamp((roughness - kSheenRoughnessFloor) / (1.0f - kSheenRoughnessFloor), 0.0f, 1.0f) * kLastRow;
    const int x0 = std::min(int(fx), kSheenAlbedoColumns - 2), y0 = std::min(int(fy), kSheenAlbedoRows - 2);
    const float tx = fx - float(x0), ty = fy - float(y0);
    const float* row0 = table + y0 * kSheenAlbedoColumns + x0;
    const float* row1 = row0 + kSheenAlbedoColumns;
    const float top = row0[0] + (row0[1] - row0[0]) * tx, bottom = row1[0] + (row1[1] - row1[0]) * tx;
    return top + (bottom - top) * ty;
}

/// The albedo integrated directly in double: int_H D V n.l dl over the hemisphere by the
/// midpoint rule on `steps` x 2 `steps` cells (in sqrt(n.l) and azimuth). At 16 steps, the
/// table's, it is within 0.0014 of 800 steps (the worst: a rough sheen seen head-on, where D's
/// square root of sin² has an unbounded slope); tests take it finer as the reference.
double sheenAlbedoIntegral(double nDotV, double roughness, int steps);

}  // namespace cuberille::raster
