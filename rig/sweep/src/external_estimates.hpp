// The sweep's external estimators (sweep file [[estimator]],
// docs/external-estimators.md): started once per sweep, asked about every
// frame after the built-in solvers, their answers stored as the estimates of
// solver "ext:NAME" beside them. Whatever an estimator does, the frame goes
// on: its failure is stored as that estimator's failed estimate and the
// reason as a run event (kind "estimator").
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "db/store/records.hpp"
#include "rig/estimator/external_estimator.hpp"
#include "rig/estimator/frame_folder.hpp"
#include "run_log.hpp"
#include "vision/camera.hpp"
#include "vision/frame_measurement.hpp"
#include "vision/target.hpp"

namespace rig::sweep {

class ExternalEstimates {
 public:
  // Nothing starts until start(). camera and target must outlive this.
  ExternalEstimates(const std::vector<estimator::EstimatorSpec>& specs,
                    const vision::Camera& camera, const vision::Target& target);
  // Stops every estimator (end of file on its stdin, 1 s to exit, then
  // SIGKILL); the run's temporary frame folder goes with frame_folder_.
  ~ExternalEstimates();

  bool empty() const { return estimators_.empty(); }
  std::vector<std::string> solver_names() const;

  // Starts every estimator and records how each start went.
  void start(RunLog& log);

  // Asks every estimator about one frame and appends their estimates to
  // `frame`. saved_png: the frame as the run saved it, when it did; otherwise
  // the image is written losslessly as PNG into a folder owned by this run
  // (estimator::FrameFolder). With every estimator disabled, nothing is
  // written and each stores its "disabled" failure. Adds each estimator's round
  // trip to solve_s["ext:NAME"], seconds. Throws std::runtime_error only when
  // the frame cannot be written as PNG.
  void measure(std::int64_t index, const cv::Mat& image,
               const std::optional<std::string>& saved_png, const vision::FrameMeasurement& m,
               db::store::FrameRecord& frame, std::map<std::string, double>& solve_s, RunLog& log);

 private:
  void log_events(estimator::ExternalEstimator& e, std::optional<std::int64_t> index, RunLog& log);

  const vision::Camera& camera_;
  const vision::Target& target_;
  std::vector<std::unique_ptr<estimator::ExternalEstimator>> estimators_;
  estimator::FrameFolder frame_folder_;  // frames when the run saves none
};

// The stored estimate of one external pose: the pose, its reprojection RMS
// against rig's detected corners of the pose's scope (the estimator's own
// corners when rig detected none there), and for the pose marker's scope the
// generalization error (paper §3.2) against the other detected markers.
// Without corners to check it against, or with the target behind the camera,
// it is stored as not converged ("estimator_no_corners", "behind_camera").
db::store::EstimateRecord external_estimate_record(
    const std::string& solver, const estimator::ExternalPose& pose, const vision::Camera& camera,
    const vision::Target& target, const std::vector<vision::Detection>& detections, double time_us);

// The stored failure of an estimator on a frame: scope "target", not
// converged, termination "estimator_<kind>" (estimator::to_string).
db::store::EstimateRecord external_failure_record(const std::string& solver,
                                                  const std::string& termination);

}  // namespace rig::sweep
