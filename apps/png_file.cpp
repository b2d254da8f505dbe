#include "apps/png_file.h"

#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include <spng.h>

#include "scene/input_error.h"

namespace cuberille::apps {
namespace {

struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
};
struct ContextFree {
    void operator()(spng_ctx* c) const { spng_ctx_free(c); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

/// zlib's fastest level and one filter (Sub) for every row, instead of libspng's default (level
/// 6, the best of five filters tried per row). Measured on this project's renders at 1920x1080
/// (a dragon on a plain background; the textured demo scene): 40-72 ms against 199-235 ms for
/// the default, files 12-48% larger (193 against 131 kB; 699 against 621 kB). Encoding was half
/// of a small render's whole process; a PNG written once and read by people or a test suite is
/// worth more fast than small.
constexpr int kPngCompressionLevel = 1;
constexpr int kPngFilterChoice = SPNG_FILTER_CHOICE_SUB;
using Context = std::unique_ptr<spng_ctx, ContextFree>;

std::string failure(const std::filesystem::path& path, const char* what, int error) {
    return path.string() + ": " + what + ": " + spng_strerror(error);
}

}  // namespace

void writePng(const std::filesystem::path& path, int width, int height, int channels, int bits,
              const std::vector<uint8_t>& pixels) {
    if (channels != 3 && channels != 4) throw std::invalid_argument("writePng: 3 or 4 channels");
    if (bits != 8 && bits != 16) throw std::invalid_argument("writePng: 8 or 16 bits");
    File file(std::fopen(path.c_str(), "wb"));
    if (!file) throw std::runtime_error(path.string() + ": cannot open for writing");
    Context ctx(spng_ctx_new(SPNG_CTX_ENCODER));
    if (!ctx) throw std::bad_alloc();
    spng_ihdr ihdr{};
    ihdr.width = uint32_t(width);
    ihdr.height = uint32_t(height);
    ihdr.bit_depth = uint8_t(bits);
    ihdr.color_type = channels == 4 ? SPNG_COLOR_TYPE_TRUECOLOR_ALPHA : SPNG_COLOR_TYPE_TRUECOLOR;
    int error = spng_set_png_file(ctx.get(), file.get());
    if (!error) error = spng_set_ihdr(ctx.get(), &ihdr);
    if (!error) error = spng_set_option(ctx.get(), SPNG_IMG_COMPRESSION_LEVEL, kPngCompressionLevel);
    if (!error) error = spng_set_option(ctx.get(), SPNG_FILTER_CHOICE, kPngFilterChoice);
    // The pixels are sRGB-encoded (raster/srgb.h): an sRGB chunk says so (rendering intent 0,
    // perceptual), so viewers apply no gamma of their own.
    if (!error) error = spng_set_srgb(ctx.get(), 0);
    if (!error) error = spng_encode_image(ctx.get(), pixels.data(), pixels.size(), SPNG_FMT_PNG, SPNG_ENCODE_FINALIZE);
    if (error) throw std::runtime_error(failure(path, "cannot write PNG", error));
    if (std::fflush(file.get()) != 0 || std::ferror(file.get()))
        throw std::runtime_error(path.string() + ": cannot write PNG: write failed (disk full?)");
}

raster::Image readPng(const std::filesystem::path& path) {
    File file(std::fopen(path.c_str(), "rb"));
    if (!file) throw scene::InputError(path.string() + ": cannot open");
    Context ctx(spng_ctx_new(0));
    if (!ctx) throw std::bad_alloc();
    spng_ihdr ihdr{};
    int error = spng_set_png_file(ctx.get(), file.get());
    if (!error) error = spng_get_ihdr(ctx.get(), &ihdr);
    if (error) throw scene::InputError(failure(path, "cannot read PNG", error));
    // 16-bit files keep their precision; everything else is expanded to 8-bit RGBA.
    const bool wide = ihdr.bit_depth == 16;
    const int format = wide ? SPNG_FMT_RGBA16 : SPNG_FMT_RGBA8;
    size_t bytes = 0;
    error = spng_decoded_image_size(ctx.get(), format, &bytes);
    if (error) throw scene::InputError(failure(path, "cannot read PNG", error));
    std::vector<uint8_t> pixels(bytes);
    error = spng_decode_image(ctx.get(), pixels.data(), bytes, format, SPNG_DECODE_TRNS);
    if (error) throw scene::InputError(failure(path, "cannot read PNG", error));
    raster::Image image;
    image.width = int(ihdr.width);
    image.height = int(ihdr.height);
    const size_t values = size_t(image.width) * image.height * 4;
    image.rgba.resize(values);
    if (wide) {
        const uint16_t* v = reinterpret_cast<const uint16_t*>(pixels.data());  // host order (spng)
        for (size_t i = 0; i < values; ++i) image.rgba[i] = float(v[i]) / 65535.0f;
    } else {
        for (size_t i = 0; i < values; ++i) image.rgba[i] = float(pixels[i]) / 255.0f;
    }
    return image;
}

}  // namespace cuberille::apps
