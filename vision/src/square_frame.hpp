// Internal: the frame of the square formed by the first four correspondences,
// shared by the solvers that work on the pose marker (analytic, opencv_ippe_square).
#pragma once

#include "vision/correspondences.hpp"

namespace vision::detail {

// T_target_square: origin at the square's centre, x along A->B, y along A->D,
// z = x cross y. Precondition: c.square_side_m is set (the first four object
// points are a square A, B, C, D).
Pose square_in_target(const Correspondences& c);

}  // namespace vision::detail
