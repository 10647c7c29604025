#include "vision/solvers.hpp"

#include <stdexcept>

#include "vision/pose_analytic.hpp"
#include "vision/pose_ekf.hpp"
#include "vision/pose_ippe.hpp"
#include "vision/pose_lm.hpp"
#include "vision/pose_oi.hpp"
#include "vision/pose_opencv.hpp"

namespace vision {

const std::vector<std::string>& solver_names() {
  static const std::vector<std::string> names = {
      "analytic",         "oi",          "hybrid_oi", "ekf",
      "hybrid_ekf",       "ippe",        "lm",        "opencv_ippe_square",
      "opencv_iterative", "opencv_sqpnp"};
  return names;
}

std::unique_ptr<PoseSolver> make_solver(const std::string& name) {
  if (name == "analytic") return std::make_unique<AnalyticSolver>();
  if (name == "oi") return std::make_unique<OiSolver>();
  if (name == "hybrid_oi") return std::make_unique<HybridOiSolver>();
  if (name == "ekf") return std::make_unique<EkfSolver>();
  if (name == "hybrid_ekf") return std::make_unique<HybridEkfSolver>();
  if (name == "ippe") return std::make_unique<IppeSolver>();
  if (name == "lm") return std::make_unique<LmSolver>();
  if (name == "opencv_ippe_square")
    return std::make_unique<OpenCvSolver>(OpenCvSolver::Method::kIppeSquare);
  if (name == "opencv_iterative")
    return std::make_unique<OpenCvSolver>(OpenCvSolver::Method::kIterative);
  if (name == "opencv_sqpnp") return std::make_unique<OpenCvSolver>(OpenCvSolver::Method::kSqpnp);
  std::string known;
  for (const auto& n : solver_names())
    known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown pose solver '" + name + "' (expected one of: " + known +
                              ")");
}

std::vector<std::unique_ptr<PoseSolver>> make_all_solvers() {
  std::vector<std::unique_ptr<PoseSolver>> all;
  for (const auto& n : solver_names())
    all.push_back(make_solver(n));
  return all;
}

}  // namespace vision
