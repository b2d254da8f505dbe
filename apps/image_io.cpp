#include "apps/image_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <unistd.h>

#include "apps/oiio_module.h"
#include "scene/environment_map.h"
#include "apps/png_file.h"
#include "render/display_image.h"
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
            error = oiioModule().writeJpeg(temp.string(), image.width, image.height, render::encodeDisplayPixels(image, false, 8),
                                           options.jpegQuality);
        else
            writePng(temp, image.width, image.height, options.alpha ? 4 : 3, options.pngBits,
                     render::encodeDisplayPixels(image, options.alpha, options.pngBits));
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

void registerEnvironmentReaders() {
    scene::registerEnvironmentReader(".exr", [](const std::filesystem::path& path) {
        const raster::Image rgba = readImage(path);
        scene::EquirectangularImage rgb{rgba.width, rgba.height, std::vector<float>(size_t(rgba.width) * size_t(rgba.height) * 3)};
        for (size_t i = 0; i < size_t(rgba.width) * size_t(rgba.height); ++i)
            for (int k = 0; k < 3; ++k) rgb.rgb[3 * i + size_t(k)] = rgba.rgba[4 * i + size_t(k)];
        return rgb;
    });
}

}  // namespace cuberille::apps
