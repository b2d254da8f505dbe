#pragma once
// PNG files in the process itself (read by libspng; written here, deflated in parallel bands):
// the format nearly every run writes, so a render never loads OpenImageIO and the hundreds of
// libraries it pulls in (apps/oiio_module.h).

#include <cstdint>
#include <filesystem>
#include <vector>

#include "raster/resolve.h"

namespace cuberille::apps {

/// Writes pixels of 3 (RGB) or 4 (RGBA) channels of 8 or 16 bits (16-bit samples in host byte
/// order), row-major, top row first, marked sRGB. Throws std::runtime_error naming the file.
void writePng(const std::filesystem::path& path, int width, int height, int channels, int bits,
              const std::vector<uint8_t>& pixels);

inline void writePng8(const std::filesystem::path& path, int width, int height, int channels,
                      const std::vector<uint8_t>& pixels) {
    writePng(path, width, height, channels, 8, pixels);
}

/// Any PNG (grey, palette, RGB, with or without alpha, 1 to 16 bits) as float RGBA: the file's
/// values scaled to [0, 1], no sRGB decoding, alpha 1 where the file has none. Throws
/// scene::InputError naming the file when it is not a PNG it can read.
raster::Image readPng(const std::filesystem::path& path);

}  // namespace cuberille::apps
