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

enum class ImageFormat { Png, Exr, Jpeg };

/// How an image is written. An image with alpha holds premultiplied colour (what the resolve
/// of a transparent background gives): EXR keeps it so (EXR's convention); PNG gets straight
/// colour and an alpha channel; JPEG has no alpha and refuses it.
struct ImageWriteOptions {
    bool alpha = false;
    int pngBits = 8;  // 8 or 16
    int jpegQuality = 92;
};

/// The format for a path's extension (.png, .exr, .jpg, .jpeg); throws scene::InputError for
/// others.
ImageFormat imageFormatFor(const std::filesystem::path& path);

/// Throws std::runtime_error naming the file on failure (exit code 1).
void writeImageAtomically(const std::filesystem::path& path, const raster::Image& image,
                          const ImageWriteOptions& options = {});

/// Lets the library read OpenEXR environment maps (--environment FILE.exr) through this
/// program's OpenImageIO module, which is loaded only when such a file is read.
void registerEnvironmentReaders();

/// Reads a PNG, or any image OpenImageIO reads, as float RGBA (8-bit formats decoded from sRGB to
/// linear is NOT applied: values are the file's, scaled to [0, 1]).
raster::Image readImage(const std::filesystem::path& path);

}  // namespace cuberille::apps
