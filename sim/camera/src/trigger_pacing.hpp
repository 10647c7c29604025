// Keeps Aravis's camera thread from busy-waiting between frame times
// (private to sim_camera; trigger_pacing.cpp says why and how).
#pragma once

#include <arv.h>

namespace sim::camera::detail {

// Marks the calling thread as `camera`'s thread, the one Aravis runs the
// fill callback on: from then on, a wait of that thread's that would spin
// sleeps until the camera's next frame time instead (a trigger period in
// software trigger mode). `camera` must outlive the thread, as Aravis's
// ArvGvFakeCamera guarantees (it joins the thread before it drops the
// camera). Cheap: a thread-local store.
void pace_camera_thread(ArvFakeCamera* camera);

}  // namespace sim::camera::detail
