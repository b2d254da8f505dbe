// Image files: PNG in the process (libspng), EXR through the OpenImageIO module.

#include <gtest/gtest.h>

#include <spng.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include <tbb/global_control.h>

#include "apps/image_io.h"
#include "apps/png_file.h"
#include "raster/srgb.h"
#include "scene/input_error.h"
#include "tests/temp_paths.h"

namespace cuberille::testing {
namespace {

namespace fs = std::filesystem;

/// A PNG of any colour type and bit depth, encoded by libspng from `pixels` in the PNG's own
/// layout (16-bit samples in host order, as libspng takes them).
void writeRawPng(const fs::path& path, int width, int height, uint8_t colorType, uint8_t bitDepth,
                 const std::vector<uint8_t>& pixels, const spng_plte* palette = nullptr, const spng_trns* trns = nullptr) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_TRUE(f);
    spng_ctx* ctx = spng_ctx_new(SPNG_CTX_ENCODER);
    spng_ihdr ihdr{};
    ihdr.width = uint32_t(width);
    ihdr.height = uint32_t(height);
    ihdr.bit_depth = bitDepth;
    ihdr.color_type = colorType;
    spng_set_png_file(ctx, f);
    spng_set_ihdr(ctx, &ihdr);
    if (palette) spng_set_plte(ctx, const_cast<spng_plte*>(palette));
    if (trns) spng_set_trns(ctx, const_cast<spng_trns*>(trns));
    EXPECT_EQ(spng_encode_image(ctx, pixels.data(), pixels.size(), SPNG_FMT_PNG, SPNG_ENCODE_FINALIZE), 0);
    spng_ctx_free(ctx);
    std::fclose(f);
}

class ImageFiles : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = uniqueTempPath(std::string("image-files-") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_;
};

void expectPixel(const raster::Image& im, int x, int y, float r, float g, float b, float a) {
    const float* p = im.pixel(x, y);
    EXPECT_EQ(p[0], r) << x << "," << y;
    EXPECT_EQ(p[1], g) << x << "," << y;
    EXPECT_EQ(p[2], b) << x << "," << y;
    EXPECT_EQ(p[3], a) << x << "," << y;
}

TEST_F(ImageFiles, PngReadsEveryColourTypeAndBitDepthAsTheFilesValues) {
    // Grey 8-bit: grey in R, G and B, opaque.
    writeRawPng(dir_ / "grey8.png", 2, 1, SPNG_COLOR_TYPE_GRAYSCALE, 8, {0, 200});
    raster::Image im = apps::readImage(dir_ / "grey8.png");
    ASSERT_EQ(im.width, 2);
    ASSERT_EQ(im.height, 1);
    expectPixel(im, 0, 0, 0.0f, 0.0f, 0.0f, 1.0f);
    expectPixel(im, 1, 0, 200 / 255.0f, 200 / 255.0f, 200 / 255.0f, 1.0f);
    // Grey with alpha.
    writeRawPng(dir_ / "greyalpha.png", 1, 1, SPNG_COLOR_TYPE_GRAYSCALE_ALPHA, 8, {51, 102});
    expectPixel(apps::readImage(dir_ / "greyalpha.png"), 0, 0, 0.2f, 0.2f, 0.2f, 0.4f);
    // 1-bit grey: 0 and 1 are black and white.
    writeRawPng(dir_ / "grey1.png", 2, 1, SPNG_COLOR_TYPE_GRAYSCALE, 1, {0b01000000});
    im = apps::readImage(dir_ / "grey1.png");
    expectPixel(im, 0, 0, 0.0f, 0.0f, 0.0f, 1.0f);
    expectPixel(im, 1, 0, 1.0f, 1.0f, 1.0f, 1.0f);
    // 16-bit RGBA keeps 16 bits.
    const uint16_t wide[4] = {1, 65535, 32768, 1000};
    std::vector<uint8_t> bytes(sizeof wide);
    std::memcpy(bytes.data(), wide, sizeof wide);
    writeRawPng(dir_ / "rgba16.png", 1, 1, SPNG_COLOR_TYPE_TRUECOLOR_ALPHA, 16, bytes);
    expectPixel(apps::readImage(dir_ / "rgba16.png"), 0, 0, 1 / 65535.0f, 1.0f, 32768 / 65535.0f, 1000 / 65535.0f);
    // A palette with a transparent entry (tRNS).
    spng_plte palette{};
    palette.n_entries = 2;
    palette.entries[0] = {255, 0, 0, 0};
    palette.entries[1] = {0, 0, 255, 0};
    spng_trns trns{};
    trns.n_type3_entries = 1;
    trns.type3_alpha[0] = 0;
    writeRawPng(dir_ / "palette.png", 2, 1, SPNG_COLOR_TYPE_INDEXED, 8, {0, 1}, &palette, &trns);
    im = apps::readImage(dir_ / "palette.png");
    expectPixel(im, 0, 0, 1.0f, 0.0f, 0.0f, 0.0f);
    expectPixel(im, 1, 0, 0.0f, 0.0f, 1.0f, 1.0f);
}

raster::Image smallGradient() {
    raster::Image image;
    image.width = 3;
    image.height = 2;
    for (int i = 0; i < 6; ++i) image.rgba.insert(image.rgba.end(), {i / 5.0f, 1.0f - i / 5.0f, 0.25f, 1.0f});
    return image;
}

// Under clang 14's AddressSanitizer (make asan) this process's LeakSanitizer crashes at exit
// ("Tracer caught signal 11" on a bogus dynamic-TLS range) after an EXR is written and read back
// in-process through the dlopen'd OpenImageIO module; the test itself passes. The release run
// checks it; the CLI's own EXR writes (Cli.RendersTriSceneToExrAndPng) run under ASan too.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CUBERILLE_UNDER_ASAN 1
#endif
#endif

TEST_F(ImageFiles, ExrRoundTripsTheRenderersFloatsExactly) {
#ifdef CUBERILLE_UNDER_ASAN
    GTEST_SKIP() << "LeakSanitizer (clang 14) crashes at exit after in-process EXR I/O through the dlopen'd module";
#endif
    const raster::Image image = smallGradient();
    apps::writeImageAtomically(dir_ / "out.exr", image);
    EXPECT_EQ(apps::readImage(dir_ / "out.exr").rgba, image.rgba);  // linear floats, exactly
}

TEST_F(ImageFiles, PngRoundTripsWhatTheRendererWrites) {
    const raster::Image image = smallGradient();
    apps::writeImageAtomically(dir_ / "out.png", image);
    const raster::Image png = apps::readImage(dir_ / "out.png");
    ASSERT_EQ(png.width, 3);
    ASSERT_EQ(png.height, 2);
    // PNG holds the sRGB encoding of each channel (raster/srgb.h), opaque.
    for (size_t i = 0; i < png.rgba.size(); ++i) {
        const float expected = i % 4 == 3 ? 1.0f : raster::encodeSrgb8(image.rgba[i]) / 255.0f;
        EXPECT_EQ(png.rgba[i], expected) << i;
    }
}

/// A PNG's samples in the file's own layout (16-bit in host order), decoded by libspng with its
/// CRC and Adler-32 checks on: an independent decoder for what apps::writePng encodes.
std::vector<uint8_t> decodeWithSpng(const fs::path& path, int& width, int& height, int& colorType, int& bits) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    EXPECT_TRUE(f);
    if (!f) return {};
    spng_ctx* ctx = spng_ctx_new(0);
    spng_set_png_file(ctx, f);
    spng_ihdr ihdr{};
    EXPECT_EQ(spng_get_ihdr(ctx, &ihdr), 0);
    size_t size = 0;
    EXPECT_EQ(spng_decoded_image_size(ctx, SPNG_FMT_PNG, &size), 0);
    std::vector<uint8_t> out(size);
    EXPECT_EQ(spng_decode_image(ctx, out.data(), size, SPNG_FMT_PNG, 0), 0);
    uint8_t intent = 255;
    EXPECT_EQ(spng_get_srgb(ctx, &intent), 0);  // marked sRGB, perceptual
    EXPECT_EQ(intent, 0);
    spng_ctx_free(ctx);
    std::fclose(f);
    width = int(ihdr.width), height = int(ihdr.height), colorType = ihdr.color_type, bits = ihdr.bit_depth;
    return out;
}

TEST_F(ImageFiles, PngWriterGivesItsSamplesBackForEveryLayoutAndBandCount) {
    // Sizes from one pixel to images of several deflate bands (apps/png_file.cpp cuts the
    // scanlines into bands of 256 KiB, each deflated on its own): one row, one column, a band
    // edge inside the image, a last band of one row.
    const std::pair<int, int> sizes[] = {{1, 1}, {7, 3}, {1, 3000}, {2000, 1}, {1000, 200}, {997, 263}};
    uint32_t state = 12345;
    auto next = [&] { return state = state * 1664525u + 1013904223u; };
    for (const int channels : {3, 4})
        for (const int bits : {8, 16})
            for (const auto& [width, height] : sizes) {
                std::vector<uint8_t> pixels(size_t(width) * height * channels * (bits / 8));
                // Noise in some rows (incompressible), runs in the others (long matches).
                for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = (i / 4096) % 2 ? uint8_t(next() >> 24) : uint8_t(i / 512);
                const fs::path path = dir_ / ("w" + std::to_string(width) + "x" + std::to_string(height) + ".png");
                apps::writePng(path, width, height, channels, bits, pixels);
                int w = 0, h = 0, colorType = 0, depth = 0;
                const std::vector<uint8_t> decoded = decodeWithSpng(path, w, h, colorType, depth);
                const std::string what = std::to_string(width) + "x" + std::to_string(height) + ", " +
                                         std::to_string(channels) + " channels of " + std::to_string(bits) + " bits";
                EXPECT_EQ(w, width) << what;
                EXPECT_EQ(h, height) << what;
                EXPECT_EQ(colorType, channels == 4 ? SPNG_COLOR_TYPE_TRUECOLOR_ALPHA : SPNG_COLOR_TYPE_TRUECOLOR) << what;
                EXPECT_EQ(depth, bits) << what;
                EXPECT_TRUE(decoded == pixels) << what;
            }
}

TEST_F(ImageFiles, PngBytesDoNotDependOnTheThreadCount) {
    const int width = 1200, height = 700;  // several bands
    std::vector<uint8_t> pixels(size_t(width) * height * 3);
    for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = uint8_t((i * 2654435761u) >> 13);
    auto bytesWith = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        const fs::path path = dir_ / ("t" + std::to_string(threads) + ".png");
        apps::writePng(path, width, height, 3, 8, pixels);
        std::ifstream in(path, std::ios::binary);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    };
    const std::string one = bytesWith(1);
    EXPECT_GT(one.size(), 1000u);
    EXPECT_TRUE(one == bytesWith(2));
    EXPECT_TRUE(one == bytesWith(7));
}

TEST_F(ImageFiles, ATruncatedPngIsBadInputNamingTheFile) {
    raster::Image image;
    image.width = image.height = 16;
    image.rgba.assign(16 * 16 * 4, 0.5f);
    apps::writeImageAtomically(dir_ / "whole.png", image);
    std::ifstream in(dir_ / "whole.png", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const size_t keep : {size_t(0), size_t(7), size_t(30), bytes.size() / 2}) {
        const fs::path cut = dir_ / ("cut" + std::to_string(keep) + ".png");
        std::ofstream(cut, std::ios::binary) << bytes.substr(0, keep);
        try {
            apps::readImage(cut);
            ADD_FAILURE() << "read a PNG cut to " << keep << " bytes";
        } catch (const scene::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(cut.string()), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace cuberille::testing
