#include "scene/environment_map.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <tuple>

#include "scene/input_error.h"

namespace cuberille::scene {

namespace {

std::map<std::string, EnvironmentImageReader>& readers() {
    static std::map<std::string, EnvironmentImageReader> registered;
    return registered;
}

std::string lowerCaseExtension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

// Radiance's RGBE files (Greg Ward, "Real Pixels", Graphics Gems II), read here rather than
// through stb_image: given a truncated file, the stb_image Debian ships reads zeros past the end
// and, in a run-length scanline, a run of length zero never ends (a hang, found by this file's
// tests). Every byte below is bounds-checked; what the format allows and this reader does not
// (another orientation than -Y H +X W, XYZE pixels) is refused with its name.

/// The file's bytes and a read position; running out is the caller's "truncated".
struct HdrBytes {
    const std::vector<uint8_t>& bytes;
    size_t at = 0;
    bool has(size_t n) const { return bytes.size() - at >= n; }
    /// The next line without its '\n'; false at the end of the bytes.
    bool line(std::string& out) {
        if (at >= bytes.size()) return false;
        const auto end = std::find(bytes.begin() + long(at), bytes.end(), uint8_t('\n'));
        out.assign(bytes.begin() + long(at), end);
        at = size_t(end - bytes.begin()) + (end != bytes.end());
        return true;
    }
};

/// One scanline's RGBE bytes (4 per pixel) from new-style run-length encoding: a 2, 2, width
/// marker, then each channel in runs (a count over 128: the next byte repeated count - 128
/// times) and literals (a count of 1 to 128: that many bytes).
bool runLengthScanline(HdrBytes& in, int width, std::vector<uint8_t>& rgbe, std::string& why) {
    for (int channel = 0; channel < 4; ++channel)
        for (int x = 0; x < width;) {
            if (!in.has(1)) return false;
            int count = in.bytes[in.at++];
            const bool run = count > 128;
            if (run) count -= 128;
            if (count == 0 || count > width - x) {
                why = "a run-length count of " + std::to_string(run ? count + 128 : count) + " at byte " + std::to_string(in.at - 1);
                return false;
            }
            if (!in.has(run ? 1 : size_t(count))) return false;
            for (int k = 0; k < count; ++k, ++x) rgbe[size_t(4 * x + channel)] = in.bytes[run ? in.at : in.at + size_t(k)];
            in.at += run ? 1 : size_t(count);
        }
    return true;
}

EquirectangularImage readRadianceHdr(const std::filesystem::path& path) {
    std::vector<uint8_t> bytes;
    {
        std::ifstream file(path, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
        if (file.bad()) throw InputError(path.string() + ": cannot read the environment map: " + std::strerror(errno));
    }
    auto fail = [&](const std::string& why) {
        return InputError(path.string() + ": cannot read the environment map: " + why);
    };
    HdrBytes in{bytes};
    std::string line;
    if (!in.line(line) || line.rfind("#?", 0) != 0) throw fail("not a Radiance HDR file (it does not begin with #?)");
    while (true) {  // the header's variables, up to an empty line
        if (!in.line(line)) throw fail("truncated in the header");
        if (line.empty()) break;
        if (line.rfind("FORMAT=", 0) == 0 && line != "FORMAT=32-bit_rle_rgbe")
            throw fail("pixels of " + line + " (only 32-bit_rle_rgbe is read)");
    }
    int width = 0, height = 0;
    char yAxis[3] = {}, xAxis[3] = {};
    if (!in.line(line) || std::sscanf(line.c_str(), "%2s %d %2s %d", yAxis, &height, xAxis, &width) != 4)
        throw fail("no resolution line after the header");
    if (std::string(yAxis) != "-Y" || std::string(xAxis) != "+X")
        throw fail("the orientation " + line + " (only -Y height +X width, rows from the top, is read)");
    if (width < 1 || height < 1 || width > (1 << 16) || height > (1 << 16))
        throw fail("a size of " + std::to_string(width) + "x" + std::to_string(height) + " (each side 1 to 65536)");
    const std::string truncated =
        "truncated (the file ends before its " + std::to_string(width) + "x" + std::to_string(height) + " pixels do)";
    // Before allocating: the fewest bytes those pixels can take (a run-length line in runs of 127,
    // 2 bytes each, per channel, after its 4-byte marker; a flat one 4 bytes a pixel), so a small
    // file cannot ask for gigabytes.
    const bool alwaysFlat = width < 8 || width > 0x7fff;
    const size_t leastLineBytes = alwaysFlat ? 4 * size_t(width) : 4 + 4 * 2 * ((size_t(width) + 126) / 127);
    if (!in.has(leastLineBytes * size_t(height))) throw fail(truncated);
    EquirectangularImage image{width, height, std::vector<float>(size_t(width) * size_t(height) * 3)};
    std::vector<uint8_t> rgbe(size_t(width) * 4);
    bool flat = alwaysFlat;  // the encoder's own rule: such lines are never run-length
    for (int y = 0; y < height; ++y) {
        if (!flat) {
            if (!in.has(4)) throw fail(truncated);
            const uint8_t* m = &in.bytes[in.at];
            flat = !(m[0] == 2 && m[1] == 2 && (m[2] & 0x80) == 0);  // a file of flat pixels
            if (!flat) {
                if ((m[2] << 8 | m[3]) != width) throw fail("a scanline of " + std::to_string(m[2] << 8 | m[3]) + " pixels in an image " +
                                                            std::to_string(width) + " wide (row " + std::to_string(y) + ")");
                in.at += 4;
                std::string why;
                if (!runLengthScanline(in, width, rgbe, why)) throw fail(why.empty() ? truncated : why + " (row " + std::to_string(y) + ")");
            }
        }
        if (flat) {
            if (!in.has(rgbe.size())) throw fail(truncated);
            std::copy_n(in.bytes.begin() + long(in.at), rgbe.size(), rgbe.begin());
            in.at += rgbe.size();
        }
        for (int x = 0; x < width; ++x) {  // RGBE: mantissas over 256, times 2^(E - 128)
            const uint8_t* p = &rgbe[size_t(4 * x)];
            const float scale = p[3] ? std::ldexp(1.0f, int(p[3]) - (128 + 8)) : 0.0f;
            float* out = &image.rgb[3 * (size_t(y) * size_t(width) + size_t(x))];
            out[0] = float(p[0]) * scale, out[1] = float(p[1]) * scale, out[2] = float(p[2]) * scale;
        }
    }
    return image;
}

/// What a prepared environment is kept under: its name, its intensity, and for a file the time
/// it was last written, so a file changed on disk is read again.
using EnvironmentKey = std::tuple<std::string, float, std::filesystem::file_time_type>;

}  // namespace

void registerEnvironmentReader(const std::string& extension, EnvironmentImageReader reader) {
    readers()[extension] = std::move(reader);
}

EquirectangularImage readEquirectangularImage(const std::filesystem::path& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw InputError(path.string() + ": no such environment map (give an .hdr or .exr file, or `neutral`)");
    const std::string ext = lowerCaseExtension(path);
    EquirectangularImage image;
    if (ext == ".hdr") {
        image = readRadianceHdr(path);
    } else if (auto it = readers().find(ext); it != readers().end()) {
        image = it->second(path);
    } else {
        throw InputError(path.string() + ": cannot read an environment map of this kind (" + (ext.empty() ? "no extension" : ext) +
                         "); give a Radiance .hdr or an OpenEXR .exr file");
    }
    // An equirectangular map spans 360 x 180 degrees: twice as wide as high, within a texel.
    if (image.width < 2 || image.height < 1 || std::abs(image.width - 2 * image.height) > 1)
        throw InputError(path.string() + ": an environment map must be equirectangular, twice as wide as it is high; this one is " +
                         std::to_string(image.width) + "x" + std::to_string(image.height));
    return image;
}

std::shared_ptr<const raster::EnvironmentLight> loadEnvironment(const std::string& name, float intensity) {
    if (!std::isfinite(intensity) || intensity < 0.0f)
        throw InputError("--environment-intensity: " + std::to_string(intensity) + " is not a finite number >= 0");
    static std::mutex mutex;
    static std::map<EnvironmentKey, std::shared_ptr<const raster::EnvironmentLight>> prepared;
    std::filesystem::file_time_type written{};
    if (name != "neutral") {
        std::error_code ec;
        written = std::filesystem::last_write_time(name, ec);
    }
    const EnvironmentKey key{name, intensity, written};
    std::lock_guard lock(mutex);
    if (auto it = prepared.find(key); it != prepared.end()) return it->second;
    std::shared_ptr<const raster::EnvironmentLight> environment;
    if (name == "neutral") {
        environment = std::make_shared<raster::EnvironmentLight>(raster::EnvironmentLight::neutral(intensity));
    } else {
        const EquirectangularImage image = readEquirectangularImage(name);
        environment = std::make_shared<raster::EnvironmentLight>(
            raster::EnvironmentLight::fromEquirectangular(image.width, image.height, image.rgb.data(), intensity));
    }
    prepared.emplace(key, environment);
    return environment;
}

}  // namespace cuberille::scene
