// The registry of pose solvers: every solver the controller runs on each frame.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "vision/pose_solver.hpp"

namespace vision {

// Names of every registered solver, in the order they are run and reported:
// analytic, oi, hybrid_oi, ekf, hybrid_ekf, ippe, lm, opencv_ippe_square,
// opencv_iterative, opencv_sqpnp.
const std::vector<std::string>& solver_names();

// One instance of every registered solver, default options, in solver_names() order.
std::vector<std::unique_ptr<PoseSolver>> make_all_solvers();

// The solver called `name`. Throws std::invalid_argument listing the known
// names when there is none.
std::unique_ptr<PoseSolver> make_solver(const std::string& name);

}  // namespace vision
