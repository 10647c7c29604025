// The paper's own figures (Maidi, Didier, Ababsa, Mallem 2010, Tables 2-6 and
// §3, DOI 10.1007/s00138-008-0170-y), shown beside ours, as printed there; the paper computed them
// on 1,400 poses (Tables 2-3) and 1,939 bench positions (Tables 4-6) with its own marker and
// camera.
#include "db/report/report.hpp"

namespace db::report {

std::optional<PaperValues> paper_values(const std::string& solver) {
  // label, Table 2 (mean, variance, sd), Table 3 (mean, variance, sd),
  // Table 4 (a, se, b, se), Table 5 (RMS, variance), Table 6 (mean error,
  // variance, sd, time), time per pose (§3, on a Pentium III 1.1 GHz).
  if (solver == "analytic") {
    return PaperValues{"Anal. algo.", 0.5421, 0.0694,    0.2634, 10.9562, 48.0473,
                       6.9316,        1.0081, 0.0009,    0.0068, 0.0007,  0.0069,
                       4.8205e-05,    0.0168, 6.9574e-6, 0.0026, 660,     19};
  }
  if (solver == "hybrid_oi") {
    return PaperValues{"H. OI",    0.4671, 0.0373,    0.1932, 17.4712, 93.5641,
                       9.6729,     1.0084, 0.0004,    0.0068, 0.0005,  0.0050,
                       2.5045e-05, 0.0057, 7.0165e-6, 0.0026, 21420,   153};
  }
  if (solver == "ekf") {
    return PaperValues{"EKF",   3.2050, 0.5272, 0.7261,  16.0005, 450.2530,
                       21.2192, 2.6034, 0.2849, -1.1006, 0.3488,  3.3241,
                       11.0498, 0.0030, 0.3567, 0.5973,  1894200, 13530};
  }
  if (solver == "hybrid_ekf") {
    return PaperValues{"H. EKF",   0.4651, 0.0360,    0.1897, 9.8435, 28.9559,
                       5.3811,     1.0071, 0.0003,    0.0087, 0.0003, 0.0033,
                       1.0808e-05, 0.0046, 3.6445e-6, 0.0019, 15680,  112};
  }
  return std::nullopt;
}

}  // namespace db::report
