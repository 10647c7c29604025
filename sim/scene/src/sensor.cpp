// Sensor noise and quantization (see sensor.hpp).
#include "sensor.hpp"

#include <algorithm>
#include <cmath>

namespace sim::scene::detail {

namespace {

// Acklam's rational approximation of the inverse normal CDF (relative error
// < 1.2e-9), ample for a 16-bit table.
double inverse_normal_cdf(double p) {
  static constexpr double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                                 -2.759285104469687e+02, 1.383577518672690e+02,
                                 -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                                 -1.556989798598866e+02, 6.680131188771972e+01,
                                 -1.328068155288572e+01};
  static constexpr double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                                 -2.400758277161838e+00, -2.549732539343734e+00,
                                 4.374664141464968e+00,  2.938163982698783e+00};
  static constexpr double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                                 2.445134137142996e+00, 3.754408661907416e+00};
  constexpr double kLow = 0.02425;
  if (p < kLow) {
    const double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - kLow) return -inverse_normal_cdf(1 - p);
  const double q = p - 0.5;
  const double r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

// SplitMix64 (Steele, Lea, Flood 2014): a fast, well-mixed generator whose
// 64-bit outputs give four 16-bit table indices.
uint64_t splitmix64(uint64_t* state) {
  uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace

NormalTable::NormalTable() : table_(1u << 16) {
  for (size_t k = 0; k < table_.size(); ++k) {
    table_[k] = static_cast<float>(inverse_normal_cdf((static_cast<double>(k) + 0.5) / 65536.0));
  }
}

FixedPattern make_fixed_pattern(int width, int height, double prnu_rel, double dsnu_electrons,
                                uint64_t seed) {
  FixedPattern p;
  if (prnu_rel == 0 && dsnu_electrons == 0) return p;
  const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height);
  p.gain.resize(n);
  p.dark_offset.resize(n);
  const NormalTable normal;
  uint64_t state = seed * 0x9E6C63D0676A9A99ull + 0x2545F4914F6CDD1Dull;
  for (size_t i = 0; i < n; ++i) {
    const uint64_t bits = splitmix64(&state);
    p.gain[i] = static_cast<float>(1 + prnu_rel * normal[static_cast<uint32_t>(bits & 0xFFFFu)]);
    p.dark_offset[i] =
        static_cast<float>(dsnu_electrons * normal[static_cast<uint32_t>((bits >> 16) & 0xFFFFu)]);
  }
  return p;
}

namespace {

// The ADC: a DN on the 8-bit scale (0 .. 255 = 0 .. full well) to the code
// of an adc_bits converter. Up to 8 bits the code stays on the 8-bit scale in
// steps of 2^(8 - bits); above 8, it is 0 .. 2^bits - 1 (the same full well
// in finer steps), stored in 16 bits.
struct Quantizer {
  explicit Quantizer(int adc_bits) {
    const int bits = std::clamp(adc_bits, 1, 16);
    code_per_dn = bits > 8 ? static_cast<float>(((1 << bits) - 1) / 255.0) : 1.0f;
    step = static_cast<float>(1 << (8 - std::min(bits, 8)));
    inv_step = 1.0f / step;
    max_level =
        bits > 8 ? static_cast<float>((1 << bits) - 1) : std::floor(255.0f * inv_step) * step;
  }
  // Truncation of a non-negative value + 0.5 rounds to the nearest level.
  float operator()(float dn) const {
    const float level =
        static_cast<float>(static_cast<int>(std::max(dn, 0.0f) * code_per_dn * inv_step + 0.5f)) *
        step;
    return std::min(level, max_level);
  }
  float code_per_dn, step, inv_step, max_level;
};

// The physical path of apply_sensor (see sensor.hpp): electrons first, then
// the gain.
template <typename Out>
void apply_sensor_physical(const float* in, size_t n, const SensorModel& model,
                           const NormalTable& normal, uint64_t seed, const FixedPattern& pattern,
                           Out* o) {
  const float full_well = static_cast<float>(model.full_well_electrons);
  const float e_per_dn = static_cast<float>(model.signal_scale * model.full_well_electrons / 255.0);
  const float dn_per_e = static_cast<float>(255.0 / model.full_well_electrons * model.gain);
  const float read_var =
      static_cast<float>(model.read_noise_electrons * model.read_noise_electrons);
  const float dark = static_cast<float>(model.dark_electrons);
  const Quantizer adc(model.adc_bits);
  const bool fixed = !pattern.empty();
  uint64_t state = seed * 0xD1B54A32D192ED03ull + 0x8CB92BA72F3D8DD7ull;
  uint64_t bits = 0;
  for (size_t i = 0; i < n; ++i) {
    float e = std::max(in[i], 0.0f) * e_per_dn;
    if (fixed) e = e * pattern.gain[i] + pattern.dark_offset[i];
    e += dark;
    if (model.noise) {
      if ((i & 3) == 0) bits = splitmix64(&state);
      const float z = normal[static_cast<uint32_t>(bits & 0xFFFFu)];
      bits >>= 16;
      e += std::sqrt(std::max(e, 0.0f) + read_var) * z;
    }
    const float dn = std::clamp(e, 0.0f, full_well) * dn_per_e;
    o[i] = static_cast<Out>(adc(dn));
  }
}

// Pixels per block of apply_sensor_plain (a multiple of 4: four deviates per
// draw): the block's normal deviates are looked up first, so that the loop
// over its pixels has no table lookup and the compiler vectorises it.
constexpr size_t kSensorBlock = 256;

// The next `count` standard normal deviates into z, four per SplitMix64 draw
// (16 bits each), in the order apply_sensor_physical takes them.
void draw_normals(const NormalTable& normal, uint64_t* state, float* z, size_t count) {
  for (size_t k = 0; k < count; k += 4) {
    uint64_t bits = splitmix64(state);
    for (size_t j = k; j < std::min(k + 4, count); ++j, bits >>= 16)
      z[j] = normal[static_cast<uint32_t>(bits & 0xFFFFu)];
  }
}

// The shot and read noise of apply_sensor without a fixed pattern, dark
// signal, signal scale or gain (see sensor.hpp).
template <typename Out>
void apply_sensor_plain(const float* in, size_t n, const SensorModel& model,
                        const NormalTable& normal, uint64_t seed, Out* o) {
  const float e_per_dn = static_cast<float>(model.full_well_electrons / 255.0);
  const float dn_per_e = 1.0f / e_per_dn;
  const float read_var =
      static_cast<float>(model.read_noise_electrons * model.read_noise_electrons);
  const Quantizer adc(model.adc_bits);
  if (!model.noise) {
    for (size_t i = 0; i < n; ++i)
      o[i] = static_cast<Out>(adc(in[i]));
    return;
  }
  uint64_t state = seed * 0xD1B54A32D192ED03ull + 0x8CB92BA72F3D8DD7ull;
  float z[kSensorBlock];
  for (size_t i0 = 0; i0 < n; i0 += kSensorBlock) {
    const size_t m = std::min(kSensorBlock, n - i0);
    draw_normals(normal, &state, z, m);
    const float* block_in = in + i0;
    Out* block_out = o + i0;
    for (size_t k = 0; k < m; ++k) {
      const float dn = block_in[k];
      const float e = std::max(dn, 0.0f) * e_per_dn;
      block_out[k] = static_cast<Out>(adc(dn + std::sqrt(e + read_var) * z[k] * dn_per_e));
    }
  }
}

template <typename Out>
cv::Mat apply_sensor_as(const cv::Mat& ideal_dn, const SensorModel& model,
                        const NormalTable& normal, uint64_t seed, const FixedPattern& pattern) {
  cv::Mat out(ideal_dn.size(), cv::DataType<Out>::type);
  if (!pattern.empty() || model.dark_electrons != 0 || model.signal_scale != 1 || model.gain != 1)
    apply_sensor_physical(ideal_dn.ptr<float>(), ideal_dn.total(), model, normal, seed, pattern,
                          out.ptr<Out>());
  else
    apply_sensor_plain(ideal_dn.ptr<float>(), ideal_dn.total(), model, normal, seed,
                       out.ptr<Out>());
  return out;
}

}  // namespace

cv::Mat apply_sensor(const cv::Mat& ideal_dn, const SensorModel& model, const NormalTable& normal,
                     uint64_t seed, const FixedPattern& pattern) {
  CV_Assert(ideal_dn.type() == CV_32FC1 && ideal_dn.isContinuous());
  return model.adc_bits > 8 ? apply_sensor_as<uint16_t>(ideal_dn, model, normal, seed, pattern)
                            : apply_sensor_as<uint8_t>(ideal_dn, model, normal, seed, pattern);
}

}  // namespace sim::scene::detail
