#include "apps/png_file.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include <spng.h>
#include <tbb/parallel_for.h>
#include <zlib.h>

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

/// The image is deflated in bands of about this many filtered bytes, each band on its own thread
/// and with its own dictionary, as pigz does: zlib deflates on one core, and at 1920x1080 that was
/// the largest part of writing a render. The bands depend on the image alone, never on the
/// thread count, so the file is the same bytes on every run. 256 KiB: 24 bands for a 1080p RGB
/// image, enough for any core count here, and the lost matches across band edges cost little
/// (a window is 32 KiB; one band in eight of its first window).
constexpr size_t kDeflateBandBytes = 256 * 1024;

using Context = std::unique_ptr<spng_ctx, ContextFree>;

std::string failure(const std::filesystem::path& path, const char* what, int error) {
    return path.string() + ": " + what + ": " + spng_strerror(error);
}

/// The PNG scanlines (a filter byte, then the row) with the Sub filter (PNG 1.2, 6.3): each byte
/// minus the byte one pixel to its left. 16-bit samples are written big-endian, as PNG stores them.
void filterRows(int width, int channels, int bits, const std::vector<uint8_t>& pixels, int row0, int row1,
                uint8_t* out) {
    const size_t pixelBytes = size_t(channels) * (bits / 8), rowBytes = pixelBytes * width;
    for (int y = row0; y < row1; ++y) {
        const uint8_t* src = pixels.data() + size_t(y) * rowBytes;
        uint8_t* dst = out + size_t(y - row0) * (rowBytes + 1);
        *dst++ = 1;  // Sub
        if (bits == 16) {
            for (size_t i = 0; i < rowBytes; i += 2) {
                uint16_t v, left = 0;
                std::memcpy(&v, src + i, 2);
                if (i >= pixelBytes) std::memcpy(&left, src + i - pixelBytes, 2);
                dst[i] = uint8_t((v >> 8) - (left >> 8));
                dst[i + 1] = uint8_t((v & 0xff) - (left & 0xff));
            }
        } else {
            for (size_t i = 0; i < pixelBytes; ++i) dst[i] = src[i];
            for (size_t i = pixelBytes; i < rowBytes; ++i) dst[i] = uint8_t(src[i] - src[i - pixelBytes]);
        }
    }
}

/// One band of scanlines as raw deflate blocks that end on a byte boundary (a sync flush), or
/// end the stream (the last band), and its Adler-32.
struct DeflatedBand {
    std::vector<uint8_t> bytes;
    uLong adler = 1;
    size_t inputBytes = 0;
};

DeflatedBand deflateBand(const uint8_t* in, size_t size, bool last) {
    DeflatedBand band;
    band.inputBytes = size;
    band.adler = adler32(1, in, uInt(size));
    z_stream z{};
    // windowBits -15: raw deflate, no zlib header or trailer; the file's stream has one of each.
    if (deflateInit2(&z, kPngCompressionLevel, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK) throw std::bad_alloc();
    band.bytes.resize(deflateBound(&z, uLong(size)) + 16);
    z.next_in = const_cast<uint8_t*>(in);
    z.avail_in = uInt(size);
    z.next_out = band.bytes.data();
    z.avail_out = uInt(band.bytes.size());
    const int status = deflate(&z, last ? Z_FINISH : Z_SYNC_FLUSH);
    const bool complete = last ? status == Z_STREAM_END : status == Z_OK && z.avail_in == 0;
    band.bytes.resize(band.bytes.size() - z.avail_out);
    deflateEnd(&z);
    if (!complete) throw std::runtime_error("deflate failed");
    return band;
}

void appendBigEndian32(std::vector<uint8_t>& out, uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(uint8_t(v >> shift));
}

/// A chunk: length, type, data, and the CRC-32 of type and data (PNG 1.2, 5.3).
void appendChunk(std::vector<uint8_t>& out, const char (&type)[5], const uint8_t* data, size_t size) {
    appendBigEndian32(out, uint32_t(size));
    const size_t typeAt = out.size();
    out.insert(out.end(), type, type + 4);
    out.insert(out.end(), data, data + size);
    appendBigEndian32(out, uint32_t(crc32(0, out.data() + typeAt, uInt(size + 4))));
}

/// The whole file in memory: signature, IHDR, sRGB, one IDAT per band (together one zlib stream),
/// IEND.
std::vector<uint8_t> encodePng(int width, int height, int channels, int bits, const std::vector<uint8_t>& pixels) {
    const size_t scanlineBytes = size_t(channels) * (bits / 8) * width + 1;
    const int bandRows = int(std::max<size_t>(1, kDeflateBandBytes / scanlineBytes));
    const int bandCount = (height + bandRows - 1) / bandRows;
    std::vector<DeflatedBand> bands(size_t(bandCount), DeflatedBand{});
    tbb::parallel_for(0, bandCount, [&](int b) {
        const int row0 = b * bandRows, row1 = std::min(height, row0 + bandRows);
        std::vector<uint8_t> scanlines(size_t(row1 - row0) * scanlineBytes);
        filterRows(width, channels, bits, pixels, row0, row1, scanlines.data());
        bands[size_t(b)] = deflateBand(scanlines.data(), scanlines.size(), b == bandCount - 1);
    });

    std::vector<uint8_t> file = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<uint8_t> header;
    appendBigEndian32(header, uint32_t(width));
    appendBigEndian32(header, uint32_t(height));
    const uint8_t colorType = channels == 4 ? 6 : 2;  // truecolour with or without alpha
    header.insert(header.end(), {uint8_t(bits), colorType, 0, 0, 0});  // deflate, adaptive filters, no interlace
    appendChunk(file, "IHDR", header.data(), header.size());
    // The pixels are sRGB-encoded (raster/srgb.h): an sRGB chunk says so (rendering intent 0,
    // perceptual), so viewers apply no gamma of their own.
    const uint8_t intent = 0;
    appendChunk(file, "sRGB", &intent, 1);
    uLong adler = 1;
    for (size_t b = 0; b < bands.size(); ++b) {
        std::vector<uint8_t>& data = bands[b].bytes;
        adler = adler32_combine(adler, bands[b].adler, z_off_t(bands[b].inputBytes));
        if (b == 0) data.insert(data.begin(), {0x78, 0x01});  // zlib header: deflate, 32 KiB window, fastest
        if (b + 1 == bands.size()) appendBigEndian32(data, uint32_t(adler));
        appendChunk(file, "IDAT", data.data(), data.size());
    }
    appendChunk(file, "IEND", nullptr, 0);
    return file;
}

}  // namespace

void writePng(const std::filesystem::path& path, int width, int height, int channels, int bits,
              const std::vector<uint8_t>& pixels) {
    if (channels != 3 && channels != 4) throw std::invalid_argument("writePng: 3 or 4 channels");
    if (bits != 8 && bits != 16) throw std::invalid_argument("writePng: 8 or 16 bits");
    if (width <= 0 || height <= 0 || pixels.size() != size_t(width) * height * channels * (bits / 8))
        throw std::invalid_argument("writePng: pixels do not match the size");
    const std::vector<uint8_t> bytes = encodePng(width, height, channels, bits, pixels);
    File file(std::fopen(path.c_str(), "wb"));
    if (!file) throw std::runtime_error(path.string() + ": cannot open for writing");
    if (std::fwrite(bytes.data(), 1, bytes.size(), file.get()) != bytes.size() || std::fflush(file.get()) != 0 ||
        std::ferror(file.get()))
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
