// db::stats::StatsError: the one error of the statistics library (db_stats).
#pragma once

#include <stdexcept>
#include <string>

namespace db::stats {

// Input a statistic cannot be computed from: mismatched lengths, too few
// points for the degrees of freedom, a degenerate design (all x equal), a
// non-finite or negative uncertainty, a probability outside [0, 1]. The
// message names the function, the offending value and what was expected.
class StatsError : public std::invalid_argument {
 public:
  explicit StatsError(const std::string& what) : std::invalid_argument(what) {}
};

}  // namespace db::stats
