#include "apps/image_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <unistd.h>

#include "apps/oiio_module.h"
#include "apps/png_file.h"
#include "raster/parallel.h"
#include "raster/srgb.h"

#include "scene/file_names.h"
#include "scene/input_error.h"

namespace cuberille::apps {

ImageFormat imageFormatFor(const std::filesystem::path& path) {
    const scene::FileKind kind = scene::fileKindOf(path);
    if (kind == scene::FileKind::Png) return ImageFormat::Png;
    if (kind == scene::FileKind::Exr) return ImageFormat::Exr;
    if (kind == scene::FileKind::Jpeg) return ImageFormat::Jpeg;
    const std::string e = scene::lowerExtension(path);
    throw scene::InputError(path.string() + ": unsupported output format '" + e +
                            "' (use .png, .exr or .jpg)");
}

namespace {

/// Straight (unassociated) colour of pixel i's channel c: what PNG stores beside alpha.
float straightChannel(const raster::Image& image, size_t i, int c, bool alpha) {
    const float value = image.rgba[i * 4 + c], a = image.rgba[i * 4 + 3];
    if (!alpha) return value;
    return a > 0.0f ? value / a : 0.0f;
}

/// The image's pixels as 8- or 16-bit samples (16-bit ones as host-order pairs of bytes, as
/// libspng takes them): sRGB-encoded colour, then linear alpha when asked for. By rows on every
/// core: at 1920x1080 the encoding is 6M lookups, a sixth of a small render's whole process
/// when it ran on one.
std::vector<uint8_t> encodedPixels(const raster::Image& image, bool alpha, int bits) {
    const int channels = alpha ? 4 : 3, bytesPerSample = bits / 8;
    std::vector<uint8_t> out(size_t(image.width) * image.height * channels * bytesPerSample);
    raster::parallelFor(size_t(image.height), [&](size_t y) {
        for (size_t i = y * size_t(image.width); i < (y + 1) * size_t(image.width); ++i)
            for (int c = 0; c < channels; ++c) {
                const float v = c == 3 ? std::clamp(image.rgba[i * 4 + 3], 0.0f, 1.0f) : straightChannel(image, i, c, alpha);
                const size_t at = (i * channels + c) * bytesPerSample;
                if (bits == 8) {
                    out[at] = c == 3 ? uint8_t(std::lround(v * 255.0f)) : raster::encodeSrgb8(v);
                } else {
                    const uint16_t sample = c == 3 ? uint16_t(std::lround(v * 65535.0f)) : raster::encodeSrgb16(v);
                    std::memcpy(&out[at], &sample, 2);
                }
            }
    });
    return out;
}

}  // namespace

void writeImageAtomically(const std::filesystem::path& path, const raster::Image& image, const ImageWriteOptions& options) {
    const ImageFormat format = imageFormatFor(path);
    if (format == ImageFormat::Jpeg && options.alpha)
        throw scene::InputError(path.string() + ": JPEG has no alpha channel; write .png or .exr for a transparent background");
    const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
    // The temporary keeps the extension, which is how OpenImageIO picks the format.
    const std::filesystem::path temp =
        dir / ("." + path.stem().string() + ".tmp" + std::to_string(::getpid()) + path.extension().string());
    auto discardTemp = [&] {
        std::error_code ignored;
        std::filesystem::remove(temp, ignored);
    };
    try {
        std::string error;  // from the OpenImageIO module
        if (format == ImageFormat::Exr)
            error = oiioModule().writeExr(temp.string(), image);
        else if (format == ImageFormat::Jpeg)
            error = oiioModule().writeJpeg(temp.string(), image.width, image.height, encodedPixels(image, false, 8),
                                           options.jpegQuality);
        else
            writePng(temp, image.width, image.height, options.alpha ? 4 : 3, options.pngBits,
                     encodedPixels(image, options.alpha, options.pngBits));
        if (!error.empty()) throw std::runtime_error(path.string() + ": cannot write image: " + error);
    } catch (...) {
        discardTemp();
        throw;
    }
    std::error_code ec;
    std::filesystem::rename(temp, path, ec);
    if (ec) {
        discardTemp();
        throw std::runtime_error(path.string() + ": cannot rename the finished image into place: " + ec.message());
    }
}

raster::Image readImage(const std::filesystem::path& path) {
    if (scene::fileKindOf(path) == scene::FileKind::Png) return readPng(path);
    raster::Image image;
    const std::string error = oiioModule().readImage(path.string(), image);
    if (!error.empty()) throw scene::InputError(path.string() + ": cannot read image: " + error);
    return image;
}

}  // namespace cuberille::apps
