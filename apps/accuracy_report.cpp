#include "apps/accuracy_report.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <map>
#include <sstream>

#include "apps/atomic_file.h"

namespace cuberille::apps {
namespace {

std::string format(const char* fmt, double v) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, fmt, v);
    return buffer;
}

std::string htmlEscape(const std::string& s) {
    std::string r;
    for (char c : s) {
        switch (c) {
            case '&': r += "&amp;"; break;
            case '<': r += "&lt;"; break;
            case '>': r += "&gt;"; break;
            case '"': r += "&quot;"; break;
            default: r += c;
        }
    }
    return r;
}

std::string csvField(const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string r = "\"";
    for (char c : s) r += c == '"' ? std::string("\"\"") : std::string(1, c);
    return r + "\"";
}

std::string utcNow() {
    const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
    char buffer[32];
    std::strftime(buffer, sizeof buffer, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
    return buffer;
}

void writeText(const std::filesystem::path& path, const std::string& text) {
    AtomicOutputFile file(path);
    file.stream() << text;
    file.commit();
}

// ---------------------------------------------------------------------------------------------
// The plot: error against time on log axes.

struct LogAxis {
    double lo, hi;  // log10 of the range
    double from, to;  // pixels
    double at(double v) const { return from + (std::log10(v) - lo) / (hi - lo) * (to - from); }
};

// A range holding every value with a margin, at least 0.3 decades wide, so a knob whose errors
// differ by a few percent still spreads over the plot.
LogAxis logAxisFor(const std::vector<double>& values, double from, double to) {
    double lo = 1e300, hi = -1e300;
    for (double v : values) {
        lo = std::min(lo, std::log10(v));
        hi = std::max(hi, std::log10(v));
    }
    const double margin = std::max(0.04, 0.06 * (hi - lo));
    lo -= margin;
    hi += margin;
    if (hi - lo < 0.3) {
        const double mid = 0.5 * (lo + hi);
        lo = mid - 0.15;
        hi = mid + 0.15;
    }
    return {lo, hi, from, to};
}

// Grid values inside the axis: decades on a wide axis, 1-2-5 on a narrower one, every integer
// multiple on one under a decade.
std::vector<double> gridValues(const LogAxis& a) {
    const double span = a.hi - a.lo;
    const std::vector<double> multiples = span > 2.5   ? std::vector<double>{1}
                                          : span > 1.0 ? std::vector<double>{1, 2, 5}
                                                       : std::vector<double>{1, 2, 3, 4, 5, 6, 7, 8, 9};
    std::vector<double> values;
    for (int d = int(std::floor(a.lo)); d <= int(std::ceil(a.hi)); ++d)
        for (double m : multiples) {
            const double v = m * std::pow(10.0, d), l = std::log10(v);
            if (l >= a.lo && l <= a.hi) values.push_back(v);
        }
    return values;
}

const char* const kCurveColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2"};

bool isCurve(const AccuracyRow& r) {
    return r.setting.knob != "preset" && r.setting.knob != "defaults" && r.setting.knob != "ground truth";
}

std::string errorTimePlot(const AccuracyReport& report, const std::string& title, const std::string& yLabel,
                          double (*metric)(const AccuracyRow&)) {
    constexpr double kWidth = 760, kHeight = 440, kLeft = 70, kRight = 200, kTop = 30, kBottom = 50;
    const std::vector<AccuracyRow>& rows = report.rows;
    // Zero error has no place on a log axis: such points sit on a "0" line under the axis.
    std::vector<double> times, errors;
    for (const AccuracyRow& r : rows) {
        times.push_back(std::max(r.medianMs, 1e-3));
        if (metric(r) > 0) errors.push_back(metric(r));
    }
    if (errors.empty()) errors.push_back(1e-3);
    const LogAxis x = logAxisFor(times, kLeft, kWidth - kRight);
    const double zeroLine = kHeight - kBottom;
    const LogAxis y = logAxisFor(errors, zeroLine - 24, kTop);
    auto px = [&](size_t i) { return x.at(times[i]); };
    auto py = [&](size_t i) { return metric(rows[i]) > 0 ? y.at(metric(rows[i])) : zeroLine; };

    std::ostringstream s;
    s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << kWidth << "' height='" << kHeight
      << "' font-family='sans-serif' font-size='11'>\n";
    s << "<text x='" << kLeft << "' y='18' font-size='13' font-weight='bold'>" << htmlEscape(title) << "</text>\n";
    // Decade grid with labels.
    for (const double v : gridValues(x)) {
        const double p = x.at(v);
        s << "<line x1='" << p << "' y1='" << kTop << "' x2='" << p << "' y2='" << kHeight - kBottom
          << "' stroke='#ddd'/><text x='" << p << "' y='" << kHeight - kBottom + 16 << "' text-anchor='middle'>"
          << format("%g", v) << " ms</text>\n";
    }
    for (const double v : gridValues(y)) {
        const double p = y.at(v);
        s << "<line x1='" << kLeft << "' y1='" << p << "' x2='" << kWidth - kRight << "' y2='" << p
          << "' stroke='#ddd'/><text x='" << kLeft - 4 << "' y='" << p + 4 << "' text-anchor='end'>"
          << format("%g", v) << "</text>\n";
    }
    s << "<line x1='" << kLeft << "' y1='" << zeroLine << "' x2='" << kWidth - kRight << "' y2='" << zeroLine
      << "' stroke='#999' stroke-dasharray='2,3'/><text x='" << kLeft - 4 << "' y='" << zeroLine + 4
      << "' text-anchor='end'>0</text>\n";
    s << "<text x='" << (kLeft + kWidth - kRight) / 2 << "' y='" << kHeight - 12
      << "' text-anchor='middle'>median frame time (log)</text>\n";
    s << "<text transform='translate(16," << (kTop + kHeight - kBottom) / 2
      << ") rotate(-90)' text-anchor='middle'>" << htmlEscape(yLabel) << " (log)</text>\n";

    // The Pareto front as a staircase through its points, fastest first.
    std::vector<size_t> front;
    for (size_t i = 0; i < rows.size(); ++i)
        if (rows[i].pareto) front.push_back(i);
    std::sort(front.begin(), front.end(), [&](size_t a, size_t b) { return times[a] < times[b]; });
    if (!front.empty()) {
        s << "<polyline fill='none' stroke='#888' stroke-width='6' stroke-opacity='0.25' points='";
        for (size_t k = 0; k < front.size(); ++k) {
            if (k) s << px(front[k]) << "," << py(front[k - 1]) << " ";
            s << px(front[k]) << "," << py(front[k]) << " ";
        }
        s << "'/>\n";
    }

    // One curve per knob, along its axis.
    std::vector<std::string> knobs;
    for (const AccuracyRow& r : rows)
        if (isCurve(r) && std::find(knobs.begin(), knobs.end(), r.setting.knob) == knobs.end())
            knobs.push_back(r.setting.knob);
    for (size_t k = 0; k < knobs.size(); ++k) {
        const char* color = kCurveColors[k % std::size(kCurveColors)];
        std::vector<size_t> curve;
        for (size_t i = 0; i < rows.size(); ++i)
            if (rows[i].setting.knob == knobs[k]) curve.push_back(i);
        std::sort(curve.begin(), curve.end(),
                  [&](size_t a, size_t b) { return rows[a].setting.order < rows[b].setting.order; });
        s << "<polyline fill='none' stroke='" << color << "' stroke-width='1.5' points='";
        for (size_t i : curve) s << px(i) << "," << py(i) << " ";
        s << "'/>\n";
        for (size_t i : curve)
            s << "<circle cx='" << px(i) << "' cy='" << py(i) << "' r='3.5' fill='" << color << "'><title>"
              << htmlEscape(knobs[k] + " " + rows[i].setting.value + ": " + rows[i].commandLine)
              << "</title></circle><text x='" << px(i) + 5 << "' y='" << py(i) - 5 << "' fill='" << color
              << "' font-size='9'>" << htmlEscape(rows[i].setting.value) << "</text>\n";
        const double ly = kTop + 16 * double(k);
        s << "<line x1='" << kWidth - kRight + 12 << "' y1='" << ly << "' x2='" << kWidth - kRight + 30 << "' y2='"
          << ly << "' stroke='" << color << "' stroke-width='2'/><text x='" << kWidth - kRight + 34 << "' y='"
          << ly + 4 << "'>" << htmlEscape(knobs[k]) << "</text>\n";
    }
    // Presets, the defaults and the truth as labelled marks.
    for (size_t i = 0; i < rows.size(); ++i) {
        if (isCurve(rows[i])) continue;
        const std::string tip = htmlEscape(rows[i].setting.value + ": " + rows[i].commandLine);
        const double cx = px(i), cy = py(i);
        if (rows[i].setting.knob == "preset")
            s << "<path d='M" << cx << "," << cy - 6 << " l6,6 l-6,6 l-6,-6 z' fill='black'><title>" << tip
              << "</title></path>";
        else if (rows[i].setting.isDefault)
            s << "<circle cx='" << cx << "' cy='" << cy << "' r='7' fill='none' stroke='black' stroke-width='2'><title>"
              << tip << "</title></circle>";
        else
            s << "<rect x='" << cx - 5 << "' y='" << cy - 5 << "' width='10' height='10' fill='#555'><title>" << tip
              << "</title></rect>";
        s << "<text x='" << cx + 8 << "' y='" << cy + 12 << "' font-weight='bold'>" << htmlEscape(rows[i].setting.value)
          << "</text>\n";
    }
    const double ly = kTop + 16 * double(knobs.size()) + 8;
    s << "<text x='" << kWidth - kRight + 12 << "' y='" << ly << "'>&#9670; preset  &#9711; defaults  &#9632; truth</text>\n";
    s << "<line x1='" << kWidth - kRight + 12 << "' y1='" << ly + 14 << "' x2='" << kWidth - kRight + 30 << "' y2='"
      << ly + 14 << "' stroke='#888' stroke-width='6' stroke-opacity='0.25'/><text x='" << kWidth - kRight + 34
      << "' y='" << ly + 18 << "'>Pareto front</text>\n";
    s << "</svg>\n";
    return s.str();
}

double rmseOf(const AccuracyRow& r) { return r.error.rmse; }
double shareOver1Of(const AccuracyRow& r) { return r.error.shareOver1; }

}  // namespace

nlohmann::json accuracyReportJson(const AccuracyReport& report) {
    const AccuracyOptions& o = report.options;
    nlohmann::json j;
    j["scene"] = o.scene;
    j["width"] = o.width;
    j["height"] = o.height;
    j["runsPerSetting"] = o.frames;
    j["threads"] = report.threads;
    j["machine"] = report.machine;
    j["traits"] = {{"threeD", report.traits.threeD},
                   {"voxel", report.traits.voxel},
                   {"textured", report.traits.textured},
                   {"shadowed", report.traits.shadowed}};
    j["notes"] = report.notes;
    j["rows"] = nlohmann::json::array();
    for (const AccuracyRow& r : report.rows) {
        const ImageError& e = r.error;
        j["rows"].push_back({{"knob", r.setting.knob},
                             {"value", r.setting.value},
                             {"id", r.id},
                             {"isDefault", r.setting.isDefault},
                             {"commandLine", r.commandLine},
                             {"frameMs", r.frameMs},
                             {"medianMs", r.medianMs},
                             {"minMs", r.minMs},
                             {"maxMs", r.maxMs},
                             {"setupMs", r.setupMs},
                             {"peakMib", r.peakMib},
                             {"deterministic", r.deterministic},
                             {"rmse", e.rmse},
                             {"psnrDb", std::isfinite(e.psnrDb) ? nlohmann::json(e.psnrDb) : nlohmann::json(nullptr)},
                             {"maxError", e.maxError},
                             {"shareOver1", e.shareOver1},
                             {"shareOver8", e.shareOver8},
                             {"pareto", r.pareto},
                             {"worstRegion", {r.worst.x, r.worst.y, r.worst.width, r.worst.height}},
                             {"crop", "crops/" + r.id + ".png"},
                             {"image", "renders/" + r.id + ".exr"}});
    }
    return j;
}

std::string accuracyReportCsv(const AccuracyReport& report) {
    std::ostringstream s;
    s << "knob,value,median_ms,min_ms,max_ms,setup_ms,peak_mib,rmse,psnr_db,max_error,share_over_1_255,"
         "share_over_8_255,pareto,deterministic,command_line\n";
    for (const AccuracyRow& r : report.rows) {
        const ImageError& e = r.error;
        s << csvField(r.setting.knob) << "," << csvField(r.setting.value) << "," << format("%.3f", r.medianMs) << ","
          << format("%.3f", r.minMs) << "," << format("%.3f", r.maxMs) << "," << format("%.3f", r.setupMs) << ","
          << format("%.1f", r.peakMib) << "," << format("%.6g", e.rmse) << ","
          << (std::isfinite(e.psnrDb) ? format("%.2f", e.psnrDb) : "inf") << "," << format("%.6g", e.maxError) << ","
          << format("%.6g", e.shareOver1) << "," << format("%.6g", e.shareOver8) << "," << (r.pareto ? 1 : 0) << ","
          << (r.deterministic ? 1 : 0) << "," << csvField(r.commandLine) << "\n";
    }
    return s.str();
}

std::string accuracyReportHtml(const AccuracyReport& report) {
    const AccuracyOptions& o = report.options;
    std::ostringstream h;
    h << "<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>Accuracy against time: "
      << htmlEscape(o.scene) << "</title>\n<style>body{font-family:sans-serif;max-width:1300px;margin:2em auto;"
         "color:#222}table{border-collapse:collapse;font-size:12px}td,th{border-bottom:1px solid #ddd;padding:3px 6px;"
         "text-align:right;vertical-align:top}td.l,th.l{text-align:left}code{font-size:11px}tr.pareto td:first-child"
         "{font-weight:bold}</style></head><body>\n";
    h << "<h1>Accuracy against time: " << htmlEscape(o.scene) << "</h1>\n";
    h << "<p>" << o.width << "&times;" << o.height << " pixels; each setting run " << o.frames
      << " times as its own <code>cuberille render</code> process (time: the median frame, with its shadow stage and "
         "without the once-per-scene load and BVH build; memory: the largest resident set); "
      << report.threads << " threads on " << htmlEscape(report.machine) << "; " << utcNow() << ".</p>\n";
    h << "<p>Every image is compared with the <b>ground truth</b>: 256 samples per pixel on a 16&times;16 grid "
         "through the same rasterizer, ray-traced shadows, source triangles instead of voxels. Errors are on "
         "sRGB-encoded colour in [0, 1]. Each knob is swept on its own around the <b>balanced</b> preset; the "
         "shaded band is the Pareto front (no other setting is both as fast and as accurate). Hover a point for its "
         "command line.</p>\n";
    h << errorTimePlot(report, "RMSE against time", "RMSE", rmseOf);
    h << errorTimePlot(report, "Pixels off by more than 1/255 against time", "share of pixels", shareOver1Of);
    h << "<h2>Notes</h2><ul>\n";
    for (const std::string& n : report.notes) h << "<li>" << htmlEscape(n) << "</li>\n";
    h << "</ul>\n<h2>Settings</h2>\n<table><tr><th class='l'>knob</th><th class='l'>value</th><th>median ms</th>"
         "<th>min&ndash;max ms</th><th>setup ms</th><th>peak MiB</th><th>RMSE</th><th>PSNR dB</th><th>max</th>"
         "<th>&gt;1/255</th><th>&gt;8/255</th><th class='l'>worst region: setting | truth | error &times;8"
         "<br>and its command line</th></tr>\n";
    for (const AccuracyRow& r : report.rows) {
        const ImageError& e = r.error;
        h << "<tr" << (r.pareto ? " class='pareto'" : "") << "><td class='l'>" << htmlEscape(r.setting.knob)
          << (r.pareto ? " &#9733;" : "") << "</td><td class='l'>" << htmlEscape(r.setting.value)
          << (r.setting.isDefault ? " (the tool's)" : "") << "</td><td>" << format("%.2f", r.medianMs) << "</td><td>"
          << format("%.2f", r.minMs) << "&ndash;" << format("%.2f", r.maxMs) << "</td><td>" << format("%.1f", r.setupMs)
          << "</td><td>" << format("%.0f", r.peakMib) << "</td><td>" << format("%.5f", e.rmse) << "</td><td>"
          << (std::isfinite(e.psnrDb) ? format("%.1f", e.psnrDb) : "&infin;") << "</td><td>"
          << format("%.3f", e.maxError) << "</td><td>" << format("%.2f%%", 100 * e.shareOver1) << "</td><td>"
          << format("%.2f%%", 100 * e.shareOver8) << "</td><td class='l'><img src='crops/" << htmlEscape(r.id)
          << ".png' alt='worst region at " << r.worst.x << "," << r.worst.y << "'><br><code>"
          << htmlEscape(r.commandLine) << "</code>" << (r.deterministic ? "" : " <b>runs differ</b>") << "</td></tr>\n";
    }
    h << "</table>\n<p>&#9733;: on the Pareto front. The same numbers: <a href='report.csv'>report.csv</a>, "
         "<a href='report.json'>report.json</a>.</p>\n</body></html>\n";
    return h.str();
}

void writeAccuracyReport(const AccuracyReport& report) {
    const std::filesystem::path& dir = report.options.outDir;
    writeJsonAtomically(dir / "report.json", accuracyReportJson(report));
    writeText(dir / "report.csv", accuracyReportCsv(report));
    writeText(dir / "index.html", accuracyReportHtml(report));
}

}  // namespace cuberille::apps
