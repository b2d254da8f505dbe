// Radiance .hdr files as environment maps (scene/environment_map.h): the reader against stb_image's
// on files stb_image_write encodes (run-length and flat), and every way a file can be damaged
// refused with its file and its reason, never a hang or a silent black.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <stb_image.h>
#include <stb_image_write.h>

#include "scene/environment_map.h"
#include "scene/input_error.h"
#include "tests/temp_paths.h"

namespace cuberille::testing {
namespace {

namespace fs = std::filesystem;

class RadianceHdr : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = uniqueTempPath(std::string("hdr-") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path writeBytes(const std::string& name, const std::string& header, const std::vector<uint8_t>& pixels) {
        std::ofstream out(dir_ / name, std::ios::binary);
        out << header;
        out.write(reinterpret_cast<const char*>(pixels.data()), std::streamsize(pixels.size()));
        return dir_ / name;
    }
    fs::path dir_;
};

// Random radiance over six decades, written by stb_image_write (run-length scanlines from 8
// pixels wide, flat ones below) and read back by stb_image and by this reader: the same floats.
TEST_F(RadianceHdr, ReadsWhatStbImageReadsForRunLengthAndFlatScanlines) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> exponent(-3.0f, 3.0f);
    for (const auto& [width, height] : {std::pair{64, 32}, {6, 3}, {300, 150}}) {
        std::vector<float> rgb(size_t(width) * height * 3);
        for (float& x : rgb) x = std::pow(10.0f, exponent(rng)) * float(rng() % 8 != 0);  // some black
        const fs::path path = dir_ / ("sky" + std::to_string(width) + ".hdr");
        ASSERT_NE(stbi_write_hdr(path.string().c_str(), width, height, 3, rgb.data()), 0);
        int w = 0, h = 0, channels = 0;
        float* expected = stbi_loadf(path.string().c_str(), &w, &h, &channels, 3);
        ASSERT_NE(expected, nullptr);
        const scene::EquirectangularImage got = scene::readEquirectangularImage(path);
        ASSERT_EQ(got.width, width);
        ASSERT_EQ(got.height, height);
        for (size_t i = 0; i < got.rgb.size(); ++i) ASSERT_EQ(got.rgb[i], expected[i]) << width << "x" << height << " float " << i;
        stbi_image_free(expected);
    }
}

TEST_F(RadianceHdr, DamagedFilesAreRefusedNamingTheFileAndTheFault) {
    const std::string header = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n";
    const std::vector<uint8_t> grey(4 * 8 * 4, 0x80);  // flat pixels for an 8 x 4 line-less image
    const std::vector<std::pair<fs::path, std::string>> cases = {
        {writeBytes("empty.hdr", "", {}), "does not begin with #?"},
        {writeBytes("png.hdr", "\x89PNG\r\n", {}), "does not begin with #?"},
        {writeBytes("open.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n", {}), "truncated in the header"},
        {writeBytes("xyze.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 4 +X 8\n", grey), "32-bit_rle_xyze"},
        {writeBytes("nosize.hdr", header, {}), "no resolution line"},
        {writeBytes("flipped.hdr", header + "+Y 4 +X 8\n", grey), "the orientation +Y 4 +X 8"},
        {writeBytes("huge.hdr", header + "-Y 4 +X 100000000\n", grey), "a size of 100000000x4"},
        {writeBytes("short.hdr", header + "-Y 4 +X 16\n", grey), "truncated (the file ends before its 16x4 pixels do)"},
        // The largest size allowed, in a few bytes: refused before 51 GB of floats are asked for.
        {writeBytes("vast.hdr", header + "-Y 65536 +X 65536\n", grey), "truncated (the file ends before its 65536x65536 pixels do)"},
        // A run of length zero: the scanline would never end. (Each line padded past the least
        // bytes a line of 8 can take, 12, so the size check does not refuse it first.)
        {writeBytes("zero.hdr", header + "-Y 1 +X 8\n", {2, 2, 0, 8, 0, 0, 0, 0, 0, 0, 0, 0}), "a run-length count of 0"},
        {writeBytes("overrun.hdr", header + "-Y 1 +X 8\n", {2, 2, 0, 8, 128 + 9, 7, 0, 0, 0, 0, 0, 0}), "a run-length count of 137"},
        {writeBytes("narrow.hdr", header + "-Y 1 +X 8\n", {2, 2, 0, 9, 0, 0, 0, 0, 0, 0, 0, 0}), "a scanline of 9 pixels in an image 8 wide"},
        {writeBytes("cut.hdr", header + "-Y 2 +X 8\n", {2, 2, 0, 8, 128 + 8, 1, 128 + 8, 1}), "truncated"},
    };
    for (const auto& [path, message] : cases) {
        try {
            scene::readEquirectangularImage(path);
            ADD_FAILURE() << path << " was read";
        } catch (const scene::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
        }
    }
}

// Every prefix and every single damaged byte of a small run-length file: read or refused with an
// input error, never anything else (the loop ends: a run of zero is caught).
TEST_F(RadianceHdr, EveryTruncationAndCorruptedByteIsReadOrRefused) {
    std::vector<float> rgb(size_t(16 * 8 * 3));
    for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = float(i % 7) * 0.3f;
    const fs::path source = dir_ / "source.hdr";
    ASSERT_NE(stbi_write_hdr(source.string().c_str(), 16, 8, 3, rgb.data()), 0);
    std::ifstream in(source, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const fs::path damaged = dir_ / "damaged.hdr";
    int refused = 0, read = 0;
    auto attempt = [&](const std::vector<char>& file) {
        std::ofstream(damaged, std::ios::binary).write(file.data(), std::streamsize(file.size()));
        try {
            const scene::EquirectangularImage image = scene::readEquirectangularImage(damaged);
            EXPECT_EQ(image.rgb.size(), size_t(image.width) * image.height * 3);
            ++read;
        } catch (const scene::InputError&) {
            ++refused;
        }
    };
    for (size_t n = 0; n < bytes.size(); ++n) attempt(std::vector<char>(bytes.begin(), bytes.begin() + long(n)));
    for (size_t i = 0; i < bytes.size(); ++i)
        for (int bit : {0, 7}) {
            std::vector<char> file = bytes;
            file[i] = char(file[i] ^ (1 << bit));
            attempt(file);
        }
    EXPECT_GT(refused, int(bytes.size()));  // every truncation at least
    EXPECT_GT(read, 0);
}

}  // namespace
}  // namespace cuberille::testing
