// The OpenImageIO module (apps/oiio_module.h): built as libcuberille_oiio.so, loaded on first
// use. Only its entry point is visible outside it.

#include "apps/oiio_module.h"

#include <algorithm>

#include <OpenImageIO/imageio.h>

#include "apps/frame_plot_drawing.h"

namespace cuberille::apps {
namespace {

std::string writeExr(const std::string& path, const raster::Image& image) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) return "cannot create an EXR writer: " + OIIO::geterror();
    OIIO::ImageSpec spec(image.width, image.height, 4, OIIO::TypeDesc::FLOAT);
    spec.attribute("compression", "zip");
    bool ok = out->open(path, spec) && out->write_image(OIIO::TypeDesc::FLOAT, image.rgba.data());
    ok = out->close() && ok;
    return ok ? std::string() : out->geterror();
}

std::string readImage(const std::string& path, raster::Image& image) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) return OIIO::geterror();
    const OIIO::ImageSpec& spec = in->spec();
    std::vector<float> pixels(size_t(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data())) return in->geterror();
    image.width = spec.width;
    image.height = spec.height;
    image.rgba.assign(size_t(spec.width) * spec.height * 4, 1.0f);
    for (size_t i = 0; i < size_t(spec.width) * spec.height; ++i)
        for (int c = 0; c < std::min(4, spec.nchannels); ++c) image.rgba[i * 4 + c] = pixels[i * spec.nchannels + c];
    return {};
}

std::string writeJpeg(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb, int quality) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) return "cannot create a JPEG writer: " + OIIO::geterror();
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("Compression", "jpeg:" + std::to_string(quality));
    spec.attribute("oiio:ColorSpace", "sRGB");
    bool ok = out->open(path, spec) && out->write_image(OIIO::TypeDesc::UINT8, rgb.data());
    ok = out->close() && ok;
    return ok ? std::string() : out->geterror();
}

const OiioModule kModule{OiioModule::kInterfaceVersion, writeExr, readImage, writeJpeg, drawFramePlot};

}  // namespace
}  // namespace cuberille::apps

extern "C" __attribute__((visibility("default"))) const cuberille::apps::OiioModule* cuberilleOiioModule() {
    return &cuberille::apps::kModule;
}
