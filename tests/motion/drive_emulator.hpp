// What the tests of the real driver against a Python drive emulator
// (pymodbus) share: how exact a read-back is and how long they wait.
#pragma once

#include <chrono>

namespace motion_test {

// Positions are exact: an emulator moves in whole counts and stops on the
// target count, and the driver quantizes a target to the same counts, so a
// settled read-back equals the target to within rounding of the mm <-> counts
// conversion. Millimetres.
constexpr double kExact = 1e-9;
// Starting a Python emulator takes well under a second; this bounds a broken one.
constexpr std::chrono::seconds kEmulatorStart{20};
// The longest move of these tests is 150 mm at 100 mm/s (1.5 s), the longest
// homing 0.25 s (PCON, 20 mm/s from 5 mm); 5 s bounds a broken test, with
// room for a loaded host.
constexpr std::chrono::seconds kSettle{5};

}  // namespace motion_test
