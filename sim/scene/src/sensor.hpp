// The sensor stage of the renderer: shot and read noise, gain, quantization
// (private to sim_scene).
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace sim::scene::detail {

struct SensorModel {
  double full_well_electrons = 20000;
  double read_noise_electrons = 20;
  int adc_bits = 8;
  bool noise = true;
  double signal_scale = 1;    // SensorExposure::signal_scale
  double dark_electrons = 0;  // mean dark signal of this exposure, e-
  double gain = 1;            // linear
};

// The fixed pattern of one camera (EMVA 1288 PRNU and DSNU): per pixel a gain
// 1 + prnu_rel N(0, 1) and a dark offset dsnu_electrons N(0, 1), drawn once
// from `seed`. Empty when both are 0.
struct FixedPattern {
  std::vector<float> gain;         // relative, per pixel (row-major)
  std::vector<float> dark_offset;  // electrons, per pixel
  bool empty() const { return gain.empty(); }
};
FixedPattern make_fixed_pattern(int width, int height, double prnu_rel, double dsnu_electrons,
                                uint64_t seed);

// Standard normal deviates from a table of 2^16 quantiles Phi^-1((k + 0.5) / 2^16),
// indexed by 16 random bits: exact to the table's resolution, truncated at
// +-4.3 sigma (a variance deficit of 2e-4 relative), and ~10x faster than
// Box-Muller, which matters at 420k deviates per frame.
class NormalTable {
 public:
  NormalTable();
  float operator[](uint32_t index16) const { return table_[index16]; }

 private:
  std::vector<float> table_;
};

// ideal_dn: CV_32FC1, the noise-free signal in DN (0 .. 255 = 0 .. full well).
// Returns CV_8UC1: DN = round((e + sqrt(e + read^2) * N(0, 1)) * 255 / full_well)
// with e = ideal_dn * full_well / 255 electrons (Poisson shot noise in its
// Gaussian limit, accurate for e >> 10, i.e. above ~0.1 DN at 20000 e-),
// quantized to adc_bits and clipped to 0 .. 255. With adc_bits 9 .. 16:
// CV_16UC1, the same DN times (2^adc_bits - 1) / 255, rounded and clipped to
// 0 .. 2^adc_bits - 1 (the same electrons and noise draws, a finer ADC).
//
// With a fixed pattern, a dark signal, a signal scale or a gain (the physical
// path): e = signal_scale * ideal_dn * full_well / 255 * prnu + dark + dsnu,
// e += sqrt(max(e, 0) + read^2) * N(0, 1), clipped to 0 .. full_well (the
// well saturates), DN = e * 255 / full_well * gain, quantized and clipped.
cv::Mat apply_sensor(const cv::Mat& ideal_dn, const SensorModel& model, const NormalTable& normal,
                     uint64_t seed, const FixedPattern& pattern = {});

}  // namespace sim::scene::detail
