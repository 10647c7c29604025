#pragma once
// The statistics of a report from the rows of a run (private to db_report).
#include "db/report.hpp"
#include "report_data.hpp"

namespace db::report {

// The ten distance classes of the paper (Fig. 11): [0.10, 1.00] m.
stats::EqualWidthBins distance_classes();
// Viewing angle classes for ambiguity and flips: [0, 90] degrees in 10 degree steps.
stats::EqualWidthBins viewing_angle_classes();

RunStudy compute_study(const RunData& data, const ReportOptions& options);

}  // namespace db::report
