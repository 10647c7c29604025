#pragma once
// The statistics of a report from the rows of a run (private to db_report).
#include "db/report/report.hpp"
#include "report_data.hpp"

namespace db::report {

// The ten distance classes of the paper (Fig. 11): [0.10, 1.00] m.
stats::EqualWidthBins distance_classes();
// A plan's end points (0.10 m, 1.00 m) are read back with micrometres of
// noise, which would put half of them outside the classes: a true distance
// at most this far outside [0.10, 1.00] m counts in the edge class, m.
// 5 mm is above any bench read-back error and a twentieth of a class width.
constexpr double kClassEdgeToleranceM = 0.005;
// The distance class of d (see kClassEdgeToleranceM); nullopt outside.
std::optional<std::size_t> distance_class(const stats::EqualWidthBins& bins, double d);
// Viewing angle classes for ambiguity and flips: [0, 90] degrees in 10 degree steps.
stats::EqualWidthBins viewing_angle_classes();

RunStudy compute_study(const RunData& data, const ReportOptions& options);

}  // namespace db::report
