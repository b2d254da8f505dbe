#pragma once
// The accuracy report's files (docs/accuracy.md): report.csv and report.json with one row per
// setting, and index.html with error-against-time plots as inline SVG (log axes, one curve per
// knob, presets, defaults and ground truth marked, the Pareto front drawn), the notes on
// monotonicity and on knobs not swept, and a table with each setting's command line and the crop
// of its worst region beside the truth. All written atomically.

#include <string>

#include <nlohmann/json.hpp>

#include "apps/accuracy_command.h"

namespace cuberille::apps {

nlohmann::json accuracyReportJson(const AccuracyReport& report);
std::string accuracyReportCsv(const AccuracyReport& report);
std::string accuracyReportHtml(const AccuracyReport& report);

/// Writes report.json, report.csv and index.html under report.options.outDir.
void writeAccuracyReport(const AccuracyReport& report);

}  // namespace cuberille::apps
