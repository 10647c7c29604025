// The joint bundle adjustment (calibration.hpp): one residual block per
// corner, a Huber loss, one parameter block holding every unknown.
#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <chrono>
#include <cmath>

#include "model.hpp"

namespace rig::calibrate {

const std::array<const char*, kParameterCount> kParameterNames = {"fx",
                                                                  "fy",
                                                                  "cx",
                                                                  "cy",
                                                                  "k1",
                                                                  "k2",
                                                                  "p1",
                                                                  "p2",
                                                                  "k3",
                                                                  "s1",
                                                                  "s2",
                                                                  "s3",
                                                                  "s4",
                                                                  "camera_misalignment_x_deg",
                                                                  "camera_misalignment_y_deg",
                                                                  "camera_misalignment_z_deg",
                                                                  "target_tilt_x_deg",
                                                                  "target_tilt_y_deg",
                                                                  "target_tilt_z_deg",
                                                                  "camera_to_target_x_mm",
                                                                  "camera_to_target_y_mm",
                                                                  "camera_to_target_z_mm",
                                                                  "target_scale_error"};
const std::array<const char*, kParameterCount> kParameterUnits = {
    "px", "px",  "px",  "px",  "",    "",    "",    "",   "",   "",   "", "",
    "",   "deg", "deg", "deg", "deg", "deg", "deg", "mm", "mm", "mm", ""};

int parameter_index(const std::string& name) {
  for (int i = 0; i < kParameterCount; ++i)
    if (name == kParameterNames[static_cast<std::size_t>(i)]) return i;
  return -1;
}

namespace detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.axis() * aa.angle();
}

Eigen::Matrix3d rotation(const double* r) {
  const Eigen::Vector3d v(r[0], r[1], r[2]);
  if (v.norm() == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(v.norm(), v.normalized()).toRotationMatrix();
}

}  // namespace

Parameters parameters_of(const vision::Camera& camera, const vision::RigGeometry& geometry,
                         double target_scale_error) {
  const vision::Intrinsics& k = camera.intrinsics();
  const vision::Distortion& dist = camera.distortion();
  Parameters p{k.fx,    k.fy,    k.cx,    k.cy,    dist.k1, dist.k2, dist.p1,
               dist.p2, dist.k3, dist.s1, dist.s2, dist.s3, dist.s4};
  const Eigen::Matrix3d N = vision::RigGeometry::R_bench_nominal();
  const Eigen::Vector3d m = rotation_vector(N.transpose() * geometry.T_carriage_cam.R);
  const Eigen::Vector3d tilt = rotation_vector(N.transpose() * geometry.T_bench_target.R);
  const Eigen::Vector3d d = geometry.T_bench_target.t - geometry.T_carriage_cam.t;
  for (int i = 0; i < 3; ++i) {
    p[static_cast<std::size_t>(kMisalignment + i)] = m[i];
    p[static_cast<std::size_t>(kTilt + i)] = tilt[i];
    p[static_cast<std::size_t>(kOffset + i)] = d[i];
  }
  p[kScale] = target_scale_error;
  return p;
}

vision::Camera camera_of(const Parameters& p, const vision::Camera& like) {
  vision::Distortion d{p[4], p[5], p[6], p[7], p[8]};
  d.s1 = p[kThinPrism];
  d.s2 = p[kThinPrism + 1];
  d.s3 = p[kThinPrism + 2];
  d.s4 = p[kThinPrism + 3];
  return vision::Camera({p[0], p[1], p[2], p[3]}, d, like.width_px(), like.height_px());
}

vision::RigGeometry geometry_of(const Parameters& p, const vision::RigGeometry& nominal) {
  const Eigen::Matrix3d N = vision::RigGeometry::R_bench_nominal();
  vision::RigGeometry g;
  g.T_carriage_cam.R = N * rotation(p.data() + kMisalignment);
  g.T_carriage_cam.t = nominal.T_carriage_cam.t;
  g.T_bench_target.R = N * rotation(p.data() + kTilt);
  g.T_bench_target.t =
      nominal.T_carriage_cam.t + Eigen::Vector3d(p[kOffset], p[kOffset + 1], p[kOffset + 2]);
  return g;
}

}  // namespace detail

namespace {

using detail::Parameters;

struct CornerResidual {
  double P[3];
  double x_m, y_m, u, v;
  template <typename T>
  bool operator()(const T* p, T* r) const {
    T uv[2];
    detail::project(p, P, x_m, y_m, uv);
    r[0] = uv[0] - T(u);
    r[1] = uv[1] - T(v);
    return true;
  }
};

// Scale of a parameter in the output: degrees for rotations, mm for d.
double output_scale(int i) {
  if (i == detail::kScale) return 1.0;
  if (i >= detail::kOffset) return 1000.0;
  if (i >= detail::kMisalignment) return 180.0 / detail::kPi;
  return 1.0;
}

// The parameters held: those named, and s1..s4 under the 5-coefficient model.
std::vector<int> fixed_indices(const CalibrationOptions& options) {
  std::vector<bool> held(kParameterCount, false);
  for (const std::string& name : options.fixed) {
    const int i = parameter_index(name);
    if (i < 0 || (i >= kIntrinsicCount && i != detail::kScale))
      throw CalibrationInputError("fixed parameter \"" + name +
                                  "\": expected one of fx fy cx cy k1 k2 p1 p2 k3 s1 s2 s3 s4 "
                                  "target_scale_error");
    held[static_cast<std::size_t>(i)] = true;
  }
  if (options.distortion == DistortionModel::kBrownConrady5)
    for (int i = detail::kThinPrism; i < detail::kThinPrism + 4; ++i)
      held[static_cast<std::size_t>(i)] = true;
  std::vector<int> fixed;
  for (int i = 0; i < kParameterCount; ++i)
    if (held[static_cast<std::size_t>(i)]) fixed.push_back(i);
  return fixed;
}

// The system at the solution, with the Huber loss applied: the Jacobian as
// a dense matrix in the tangent space (the free parameters' columns, in
// order; a fixed parameter has no column) and the residuals (two per corner,
// in the order of the problem's corners).
struct Linearisation {
  Eigen::MatrixXd J;
  Eigen::VectorXd r;
};

Linearisation linearise(ceres::Problem& problem) {
  ceres::Problem::EvaluateOptions eval;
  eval.apply_loss_function = true;
  ceres::CRSMatrix crs;
  std::vector<double> residuals;
  problem.Evaluate(eval, nullptr, &residuals, nullptr, &crs);
  Linearisation l{Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols),
                  Eigen::Map<const Eigen::VectorXd>(residuals.data(),
                                                    static_cast<Eigen::Index>(residuals.size()))};
  for (int row = 0; row < crs.num_rows; ++row)
    for (int k = crs.rows[static_cast<std::size_t>(row)];
         k < crs.rows[static_cast<std::size_t>(row) + 1]; ++k)
      l.J(row, crs.cols[static_cast<std::size_t>(k)]) = crs.values[static_cast<std::size_t>(k)];
  return l;
}

// Names the weakest direction of the column-scaled Jacobian when it is
// (numerically) rank deficient.
void check_rank(const Eigen::MatrixXd& J, const std::vector<bool>& is_fixed) {
  Eigen::MatrixXd Js = J;
  for (int c = 0; c < Js.cols(); ++c) {
    const double n = Js.col(c).norm();
    if (n > 0) Js.col(c) /= n;
  }
  const Eigen::MatrixXd JtJ = Js.transpose() * Js;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(JtJ);
  const double smallest = std::sqrt(std::max(0.0, eig.eigenvalues()(0)));
  const double largest = std::sqrt(eig.eigenvalues()(eig.eigenvalues().size() - 1));
  if (smallest >= kMinRelativeSingularValue * largest) return;
  Eigen::Index weakest = 0;
  eig.eigenvectors().col(0).cwiseAbs().maxCoeff(&weakest);
  int free = 0;
  for (int i = 0; i < kParameterCount; ++i) {
    if (is_fixed[static_cast<std::size_t>(i)]) continue;
    if (free++ == weakest)
      throw UnobservablePlan(std::string(kParameterNames[static_cast<std::size_t>(i)]) +
                             " is not observable from this plan: the Jacobian at the solution " +
                             "is rank deficient (relative singular value " +
                             std::to_string(smallest / largest) + ")");
  }
}

void fill_statistics(const CalibrationProblem& problem, const Parameters& p,
                     CalibrationResult* result) {
  double sum = 0;
  std::map<std::int64_t, std::pair<double, int>> by_position;
  std::map<int, std::pair<double, int>> by_marker;
  for (const CornerObservation& o : problem.corners) {
    double uv[2];
    detail::project(p.data(), o.target_point_m.data(), o.x_mm / 1000.0, o.y_mm / 1000.0, uv);
    const double e2 = std::pow(uv[0] - o.pixel.x(), 2) + std::pow(uv[1] - o.pixel.y(), 2);
    sum += e2;
    by_position[o.plan_index].first += e2;
    ++by_position[o.plan_index].second;
    by_marker[o.marker_id].first += e2;
    ++by_marker[o.marker_id].second;
  }
  const double n = static_cast<double>(problem.corners.size());
  result->rms_px = std::sqrt(sum / n);
  for (const auto& [k, s] : by_position)
    result->rms_by_position_px[k] = std::sqrt(s.first / s.second);
  for (const auto& [k, s] : by_marker)
    result->rms_by_marker_px[k] = std::sqrt(s.first / s.second);
  int free = 0;
  for (const ParameterEstimate& e : result->parameters)
    free += e.fixed ? 0 : 1;
  result->sigma_px = std::sqrt(sum / std::max(1.0, 2 * n - free));
}

// The covariance of the free parameters (tangent space), two ways. With
// B = (J^T J)^-1:
//  - independent corners: sigma^2 B, every corner coordinate an independent
//    error of sd sigma_px;
//  - clustered by bench position (the sandwich estimator, White 1980; Liang &
//    Zeger 1986): B M B, M = C / (C - 1) sum_c g_c g_c^T over the C
//    positions, g_c = J_c^T r_c the score of position c's corners. The
//    corners of one position share their errors' causes (the detector's bias
//    under that position's blur, light and viewing angle, what the lens model
//    leaves at those image points), so they are not independent; positions
//    are. With fewer than kPositionsPerParameter positions per free parameter
//    M is too poorly estimated and the first is used.
constexpr int kPositionsPerParameter = 3;

void fill_covariance(const CalibrationProblem& input, const Linearisation& l,
                     CalibrationResult* result) {
  const Eigen::Index free = l.J.cols();
  const Eigen::MatrixXd B =
      (l.J.transpose() * l.J).ldlt().solve(Eigen::MatrixXd::Identity(free, free));
  std::map<std::int64_t, Eigen::VectorXd> scores;
  for (std::size_t i = 0; i < input.corners.size(); ++i) {
    const Eigen::Index row = 2 * static_cast<Eigen::Index>(i);
    auto [it, added] = scores.try_emplace(input.corners[i].plan_index, Eigen::VectorXd::Zero(free));
    it->second += l.J.middleRows(row, 2).transpose() * l.r.segment<2>(row);
  }
  const double clusters = static_cast<double>(scores.size());
  const Eigen::MatrixXd independent = result->sigma_px * result->sigma_px * B;
  Eigen::MatrixXd V = independent;
  result->sd_method =
      "independent corners (" + std::to_string(scores.size()) + " positions: too few to cluster)";
  if (clusters >= kPositionsPerParameter * static_cast<double>(free)) {
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(free, free);
    for (const auto& [position, g] : scores)
      M.noalias() += g * g.transpose();
    V = B * (clusters / (clusters - 1) * M) * B;
    result->sd_method =
        "clustered by bench position (" + std::to_string(scores.size()) + " positions)";
  }
  result->correlation = Eigen::MatrixXd::Identity(kParameterCount, kParameterCount);
  std::vector<int> column(kParameterCount, -1);
  for (int i = 0, c = 0; i < kParameterCount; ++i)
    if (!result->parameters[static_cast<std::size_t>(i)].fixed)
      column[static_cast<std::size_t>(i)] = c++;
  for (int i = 0; i < kParameterCount; ++i) {
    const int a = column[static_cast<std::size_t>(i)];
    if (a < 0) continue;
    auto& e = result->parameters[static_cast<std::size_t>(i)];
    e.sd = std::sqrt(std::max(0.0, V(a, a))) * output_scale(i);
    e.sd_independent = std::sqrt(std::max(0.0, independent(a, a))) * output_scale(i);
    for (int j = 0; j < kParameterCount; ++j) {
      const int b = column[static_cast<std::size_t>(j)];
      if (i == j || b < 0 || V(a, a) <= 0 || V(b, b) <= 0) continue;
      result->correlation(i, j) = V(a, b) / std::sqrt(V(a, a) * V(b, b));
    }
  }
}

}  // namespace

CalibrationResult calibrate(const CalibrationProblem& input, const CalibrationOptions& options) {
  if (input.corners.empty())
    throw CalibrationInputError(input.source + ": no detected corners to calibrate from");
  check_observable(input);
  const std::vector<int> fixed = fixed_indices(options);
  std::vector<bool> is_fixed(kParameterCount, false);
  for (const int i : fixed)
    is_fixed[static_cast<std::size_t>(i)] = true;

  Parameters p = detail::parameters_of(input.nominal_camera, input.nominal_geometry);
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::HuberLoss huber(options.huber_px);
  for (const CornerObservation& o : input.corners) {
    auto* cost = new ceres::AutoDiffCostFunction<CornerResidual, 2, kParameterCount>(
        new CornerResidual{{o.target_point_m.x(), o.target_point_m.y(), o.target_point_m.z()},
                           o.x_mm / 1000.0,
                           o.y_mm / 1000.0,
                           o.pixel.x(),
                           o.pixel.y()});
    problem.AddResidualBlock(cost, &huber, p.data());
  }
  if (!fixed.empty())
    problem.SetManifold(p.data(), new ceres::SubsetManifold(kParameterCount, fixed));

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver.num_threads = options.threads;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-14;
  const auto start = std::chrono::steady_clock::now();
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  if (!summary.IsSolutionUsable())
    throw std::runtime_error(input.source + ": the bundle adjustment failed: " + summary.message);

  CalibrationResult result;
  result.camera = detail::camera_of(p, input.nominal_camera);
  result.geometry = detail::geometry_of(p, input.nominal_geometry);
  result.target_scale_error = p[detail::kScale];
  for (int i = 0; i < kParameterCount; ++i) {
    auto& e = result.parameters[static_cast<std::size_t>(i)];
    e.name = kParameterNames[static_cast<std::size_t>(i)];
    e.unit = kParameterUnits[static_cast<std::size_t>(i)];
    e.value = p[static_cast<std::size_t>(i)] * output_scale(i);
    e.fixed = is_fixed[static_cast<std::size_t>(i)];
  }
  result.corners = input.corners.size();
  result.iterations = static_cast<int>(summary.iterations.size());
  result.termination = summary.BriefReport();
  fill_statistics(input, p, &result);
  const Linearisation at_solution = linearise(problem);
  check_rank(at_solution.J, is_fixed);
  result.correlation = Eigen::MatrixXd::Identity(kParameterCount, kParameterCount);
  if (options.covariance) fill_covariance(input, at_solution, &result);
  result.solve_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

double reprojection_rms_px(const CalibrationProblem& problem, const vision::Camera& camera,
                           const vision::RigGeometry& geometry,
                           const std::vector<std::int64_t>& plan_indices,
                           double target_scale_error) {
  const Parameters p = detail::parameters_of(camera, geometry, target_scale_error);
  double sum = 0;
  std::size_t n = 0;
  for (const CornerObservation& o : problem.corners) {
    if (!plan_indices.empty() &&
        std::find(plan_indices.begin(), plan_indices.end(), o.plan_index) == plan_indices.end())
      continue;
    double uv[2];
    detail::project(p.data(), o.target_point_m.data(), o.x_mm / 1000.0, o.y_mm / 1000.0, uv);
    sum += std::pow(uv[0] - o.pixel.x(), 2) + std::pow(uv[1] - o.pixel.y(), 2);
    ++n;
  }
  return n == 0 ? 0.0 : std::sqrt(sum / static_cast<double>(n));
}

CalibrationProblem alternate_positions(const CalibrationProblem& problem, bool even) {
  CalibrationProblem half = problem;
  half.corners.clear();
  for (const CornerObservation& o : problem.corners)
    if ((o.plan_index % 2 == 0) == even) half.corners.push_back(o);
  return half;
}

HeldOutCheck held_out_check(const CalibrationProblem& problem, CalibrationOptions options) {
  options.covariance = false;
  const CalibrationProblem fit = alternate_positions(problem, true);
  const CalibrationProblem held_out = alternate_positions(problem, false);
  const CalibrationResult r = calibrate(fit, options);
  HeldOutCheck check;
  std::map<std::int64_t, int> fit_positions, held_positions;
  for (const CornerObservation& o : fit.corners)
    fit_positions[o.plan_index] = 1;
  for (const CornerObservation& o : held_out.corners)
    held_positions[o.plan_index] = 1;
  check.fit_positions = fit_positions.size();
  check.held_out_positions = held_positions.size();
  check.fit_rms_px = r.rms_px;
  check.held_out_rms_px =
      reprojection_rms_px(held_out, r.camera, r.geometry, {}, r.target_scale_error);
  return check;
}

}  // namespace rig::calibrate
