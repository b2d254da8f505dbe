// The frame plots' drawing, compiled into the OpenImageIO module (apps/oiio_module.h).
#include "apps/frame_plot_drawing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include "raster/srgb.h"

namespace cuberille::apps {
namespace {

constexpr int kMarginLeft = 90, kMarginRight = 230, kPanelGap = 36, kTitleHeight = 44, kAxisHeight = 34;
constexpr int kFontPixels = 15;
const char* kFont = "DejaVuSans";

struct Canvas {
    OIIO::ImageBuf buf;
    bool textOk = true;

    void line(int x0, int y0, int x1, int y1, const glm::vec3& c) {
        OIIO::ImageBufAlgo::render_line(buf, x0, y0, x1, y1, {c.r, c.g, c.b});
    }
    void box(int x0, int y0, int x1, int y1, const glm::vec3& c, bool fill) {
        OIIO::ImageBufAlgo::render_box(buf, x0, y0, x1, y1, {c.r, c.g, c.b}, fill);
    }
    void text(int x, int y, const std::string& s, const glm::vec3& c, int size = kFontPixels) {
        if (textOk && !OIIO::ImageBufAlgo::render_text(buf, x, y, s, size, kFont, {c.r, c.g, c.b})) textOk = false;
    }
};

/// A readable number for an axis label: 3 significant digits, k/M for large values.
std::string axisLabel(double v) {
    char s[32];
    if (v >= 1e6) std::snprintf(s, sizeof s, "%.3gM", v / 1e6);
    else if (v >= 1e4) std::snprintf(s, sizeof s, "%.3gk", v / 1e3);
    else std::snprintf(s, sizeof s, "%.3g", v);
    return s;
}

void drawPanel(Canvas& c, const PlotPanel& panel, int top, int height, int frames, const PlotLayout& layout) {
    const int left = kMarginLeft, right = layout.widthPixels - kMarginRight, bottom = top + height;
    const glm::vec3 ink(0.1f), grid(0.85f);
    double peak = 0.0;
    for (const PlotSeries& s : panel.series)
        for (double v : s.values) peak = std::max(peak, v);
    peak = peak > 0.0 ? peak * 1.05 : 1.0;
    auto xOf = [&](double frame) { return left + int(std::lround((right - left) * frame / std::max(1, frames - 1))); };
    auto yOf = [&](double v) { return bottom - int(std::lround((height - 1) * std::clamp(v / peak, 0.0, 1.0))); };
    if (layout.firstSettlingFrame >= 0 && layout.firstSettlingFrame < frames)
        c.box(xOf(layout.firstSettlingFrame), top, right, bottom, glm::vec3(0.93f, 0.93f, 0.97f), true);
    for (int k = 1; k <= 4; ++k) {  // horizontal grid at quarters, labelled
        const int y = yOf(peak / 1.05 * k / 4.0);
        c.line(left, y, right, y, grid);
        c.text(8, y + 5, axisLabel(peak / 1.05 * k / 4.0), ink, 13);
    }
    for (int f : panel.markers) c.line(xOf(f), top, xOf(f), top + 10, glm::vec3(0.8f, 0.1f, 0.1f));
    for (const PlotSeries& s : panel.series)
        for (size_t i = 1; i < s.values.size(); ++i)
            c.line(xOf(double(i - 1)), yOf(s.values[i - 1]), xOf(double(i)), yOf(s.values[i]), s.color);
    if (frames == 1)
        for (const PlotSeries& s : panel.series) c.box(left - 2, yOf(s.values[0]) - 2, left + 2, yOf(s.values[0]) + 2, s.color, true);
    c.box(left, top, right, bottom, ink, false);
    c.text(left, top - 8, panel.title, ink, 16);
    int legendY = top + 14;
    for (const PlotSeries& s : panel.series) {
        c.box(right + 14, legendY - 9, right + 30, legendY - 3, s.color, true);
        c.text(right + 38, legendY, s.name, ink, 13);
        legendY += 18;
    }
    if (!panel.markers.empty()) {
        c.line(right + 22, legendY - 12, right + 22, legendY - 2, glm::vec3(0.8f, 0.1f, 0.1f));
        c.text(right + 38, legendY, panel.markerName, ink, 13);
    }
}

}  // namespace

raster::Image drawFramePlot(const std::vector<PlotPanel>& panels, const PlotLayout& layout, std::string* warning) {
    int frames = 1;
    for (const PlotPanel& p : panels)
        for (const PlotSeries& s : p.series) frames = std::max(frames, int(s.values.size()));
    const int height = kTitleHeight + int(panels.size()) * (layout.panelHeightPixels + kPanelGap) + kAxisHeight;
    Canvas c;
    c.buf.reset(OIIO::ImageSpec(layout.widthPixels, height, 3, OIIO::TypeDesc::FLOAT));
    OIIO::ImageBufAlgo::fill(c.buf, {1.0f, 1.0f, 1.0f});
    c.text(kMarginLeft, 28, layout.title, glm::vec3(0.0f), 18);
    int top = kTitleHeight + kPanelGap - 10;
    for (const PlotPanel& p : panels) {
        drawPanel(c, p, top, layout.panelHeightPixels, frames, layout);
        top += layout.panelHeightPixels + kPanelGap;
    }
    // The shared frame axis under the last panel.
    const int right = layout.widthPixels - kMarginRight, axisY = top - kPanelGap + 18;
    for (int k = 0; k <= 4; ++k) {
        const int f = (frames - 1) * k / 4;
        const int x = kMarginLeft + (right - kMarginLeft) * k / 4;
        c.text(x - 6, axisY, std::to_string(f), glm::vec3(0.1f), 13);
    }
    c.text(right - 40, axisY + 16, "frame", glm::vec3(0.1f), 13);
    if (layout.firstSettlingFrame >= 0 && layout.firstSettlingFrame < frames)
        c.text(kMarginLeft + 120, axisY + 16, "shaded: after the path, settling", glm::vec3(0.35f), 13);
    if (!c.textOk && warning) *warning = "the plot's labels were left out: no font '" + std::string(kFont) + "' found";
    raster::Image image;
    image.width = layout.widthPixels;
    image.height = height;
    image.rgba.assign(size_t(image.width) * height * 4, 1.0f);
    std::vector<float> rgb(size_t(image.width) * height * 3);
    c.buf.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, rgb.data());
    // Drawn in display (sRGB) values; images hold linear ones, encoded again when written.
    for (size_t i = 0; i < size_t(image.width) * height; ++i)
        for (int k = 0; k < 3; ++k)
            image.rgba[i * 4 + k] = raster::decodeSrgb8(uint8_t(std::lround(std::clamp(rgb[i * 3 + k], 0.0f, 1.0f) * 255.0f)));
    return image;
}

}  // namespace cuberille::apps
