#pragma once
// Image files: PNG through libspng in the process (sRGB-encoded 8-bit RGB), EXR and other
// formats through the OpenImageIO module loaded on first use (apps/oiio_module.h); EXR gets the
// linear float RGBA values unchanged. Writes go to a temporary name in the same folder and
// are renamed into place, so a failure never leaves a torn file or clobbers a good one.

#include <cstdint>
#include <filesystem>
#include <string>

#include "raster/resolve.h"

namespace cuberille::apps {

enum class ImageFormat { Png, Exr };

/// The format for a path's extension; throws scene::InputError for others.
ImageFormat imageFormatFor(const std::filesystem::path& path);

/// Throws std::runtime_error naming the file on failure (exit code 1).
void writeImageAtomically(const std::filesystem::path& path, const raster::Image& image);

/// Reads a PNG, or any image OpenImageIO reads, as float RGBA (8-bit formats decoded from sRGB to
/// linear is NOT applied: values are the file's, scaled to [0, 1]).
raster::Image readImage(const std::filesystem::path& path);

}  // namespace cuberille::apps
