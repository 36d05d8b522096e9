// The human-readable report of `leakmon model check --report DIR`: report.md for the rig
// engineer (what was wrong, where it shows, what it was named, fitted parameters with their
// uncertainties, error before and after), held-out residuals as CSV, and plots drawn by
// matplotlib (docs/tools/model_report_plots.py, run with /usr/bin/python3).
#pragma once

#include <string>

#include "model/diagnosis.hpp"
#include "model/measured_record.hpp"

namespace leakmon::model {

// Writes DIR/report.md, DIR/residuals.csv, DIR/result.json and the figures. Returns false
// when the plotting script failed (the text report is still written).
bool write_report(const std::string& dir, const MeasuredRecord& record, const Diagnosis& d);

}  // namespace leakmon::model
