#include "apps/image_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include "raster/srgb.h"

#include "scene/file_names.h"
#include "scene/input_error.h"

namespace cuberille::apps {

ImageFormat imageFormatFor(const std::filesystem::path& path) {
    const scene::FileKind kind = scene::fileKindOf(path);
    if (kind == scene::FileKind::Png) return ImageFormat::Png;
    if (kind == scene::FileKind::Exr) return ImageFormat::Exr;
    const std::string e = scene::lowerExtension(path);
    throw scene::InputError(path.string() + ": unsupported output format '" + e +
                            "' (use .png or .exr)");
}


void writeImageAtomically(const std::filesystem::path& path, const raster::Image& image) {
    const ImageFormat format = imageFormatFor(path);
    const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
    // The temporary keeps the extension, which is how OpenImageIO picks the format.
    const std::filesystem::path temp =
        dir / ("." + path.stem().string() + ".tmp" + std::to_string(::getpid()) + path.extension().string());
    auto out = OIIO::ImageOutput::create(temp.string());
    if (!out) throw std::runtime_error(path.string() + ": cannot create image writer");
    bool ok = false;
    if (format == ImageFormat::Exr) {
        OIIO::ImageSpec spec(image.width, image.height, 4, OIIO::TypeDesc::FLOAT);
        spec.attribute("compression", "zip");
        ok = out->open(temp.string(), spec) &&
             out->write_image(OIIO::TypeDesc::FLOAT, image.rgba.data());
    } else {
        std::vector<uint8_t> rgb(size_t(image.width) * image.height * 3);
        for (size_t i = 0; i < size_t(image.width) * image.height; ++i)
            for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = raster::encodeSrgb8(image.rgba[i * 4 + c]);
        OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::UINT8);
        ok = out->open(temp.string(), spec) && out->write_image(OIIO::TypeDesc::UINT8, rgb.data());
    }
    ok = out->close() && ok;
    if (!ok) {
        std::error_code ignored;
        std::filesystem::remove(temp, ignored);
        throw std::runtime_error(path.string() + ": cannot write image: " + out->geterror());
    }
    std::error_code ec;
    std::filesystem::rename(temp, path, ec);
    if (ec) {
        std::error_code ignored;
        std::filesystem::remove(temp, ignored);
        throw std::runtime_error(path.string() + ": cannot rename the finished image into place: " + ec.message());
    }
}

raster::Image readImage(const std::filesystem::path& path) {
    auto in = OIIO::ImageInput::open(path.string());
    if (!in) throw scene::InputError(path.string() + ": cannot read image: " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    raster::Image image;
    image.width = spec.width;
    image.height = spec.height;
    std::vector<float> pixels(size_t(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
        throw scene::InputError(path.string() + ": cannot read image: " + in->geterror());
    image.rgba.assign(size_t(spec.width) * spec.height * 4, 1.0f);
    for (size_t i = 0; i < size_t(spec.width) * spec.height; ++i)
        for (int c = 0; c < std::min(4, spec.nchannels); ++c)
            image.rgba[i * 4 + c] = pixels[i * spec.nchannels + c];
    return image;
}

}  // namespace cuberille::apps
