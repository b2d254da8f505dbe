#pragma once
// The sRGB transfer function (IEC 61966-2-1) for 8-bit values: outputs are encoded when a
// resolved image goes to an 8-bit file (DESIGN.md, raster conventions), and 8-bit colours read
// from files or stored in voxel models are decoded. Both directions are table lookups, exact by
// construction: encoding compares against the 255 decision thresholds (no pow per value, and no
// libm rounding can change a result), decoding reads one of 256 precomputed values.

#include <cstddef>
#include <cstdint>

namespace cuberille::raster {

/// Linear [0, 1] to 8-bit sRGB, round to nearest; below 0 (and NaN) gives 0, above 1 gives 255.
uint8_t encodeSrgb8(float linear);
/// The same for `count` values at once (an image's rows): the tables looked up once.
void encodeSrgb8(const float* linear, size_t count, uint8_t* out);

/// Linear [0, 1] to 16-bit sRGB, round to nearest, from the transfer function in double
/// (16-bit files: PNG at --png-bits 16); below 0 (and NaN) gives 0, above 1 gives 65535.
uint16_t encodeSrgb16(float linear);

/// A display (sRGB-encoded) value in [0, 1] to linear, in double: colours a user types.
double decodeSrgb(double encoded);

/// 8-bit sRGB to linear [0, 1].
float decodeSrgb8(uint8_t encoded);

}  // namespace cuberille::raster
