// detect_corners and redetected (calibration.hpp): the saved frames of a
// calibration sweep, detected again through a calibrated camera.
#include <algorithm>
#include <future>

#include "corners.hpp"
#include "db/store/saved_frame.hpp"
#include "vision/detector_image.hpp"

namespace rig::calibrate {
namespace detail {

void append_corners(const vision::Target& target, std::int64_t plan_index, double x_mm, double y_mm,
                    int marker_id, const std::array<Eigen::Vector2d, 4>& corners_px,
                    std::vector<CornerObservation>* out) {
  const std::array<Eigen::Vector3d, 4> corners = target.corners_m(marker_id);
  for (std::size_t c = 0; c < 4; ++c)
    if (corners_px[c].allFinite())
      out->push_back(
          {plan_index, x_mm, y_mm, marker_id, static_cast<int>(c), corners[c], corners_px[c]});
}

}  // namespace detail

std::vector<CornerObservation> detect_corners(const vision::FiducialDetector& detector,
                                              const vision::Target& target,
                                              const CalibrationFrame& frame, const cv::Mat& image) {
  std::vector<CornerObservation> out;
  for (const vision::Detection& d : detector.detect(image))
    if (target.has_marker(d.id))
      detail::append_corners(target, frame.plan_index, frame.x_mm, frame.y_mm, d.id, d.corners_px,
                             &out);
  return out;
}

void check_saved_frames(const CalibrationProblem& problem) {
  if (problem.frames.empty())
    throw CalibrationInputError(problem.source +
                                ": the run saved no frames ([capture] save_frames), so its "
                                "corners cannot be detected again");
}

namespace {

// One saved frame detected again: read (its SHA-256 checked), decoded, detected.
std::vector<CornerObservation> redetect_frame(const CalibrationProblem& problem,
                                              const vision::FiducialDetector& detector,
                                              const CalibrationFrame& frame) {
  cv::Mat image;
  try {
    const std::string bytes = db::store::read_saved_frame(frame.image_path, frame.image_sha256);
    image = vision::decode_image(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(),
                                 cv::IMREAD_UNCHANGED, "recorded frame " + frame.image_path);
  } catch (const db::store::SavedFrameError& e) {
    throw CalibrationInputError(problem.source + ": " + e.what());
  } catch (const vision::ImageError& e) {
    throw CalibrationInputError(problem.source + ": " + e.what());
  }
  return detect_corners(detector, problem.target, frame, image);
}

}  // namespace

CalibrationProblem redetected(const CalibrationProblem& problem, const vision::Camera& camera,
                              int threads) {
  check_saved_frames(problem);
  const std::unique_ptr<vision::FiducialDetector> detector =
      vision::make_detector(problem.detector, camera, problem.target.family);
  // Contiguous shares of the frames, one per thread, joined in frame order.
  const std::size_t n = problem.frames.size();
  const std::size_t parts = static_cast<std::size_t>(std::clamp(threads, 1, 64));
  std::vector<std::future<std::vector<CornerObservation>>> shares;
  for (std::size_t part = 0; part < parts; ++part)
    shares.push_back(std::async(std::launch::async, [&, part] {
      std::vector<CornerObservation> corners;
      for (std::size_t i = part * n / parts; i < (part + 1) * n / parts; ++i) {
        const std::vector<CornerObservation> found =
            redetect_frame(problem, *detector, problem.frames[i]);
        corners.insert(corners.end(), found.begin(), found.end());
      }
      return corners;
    }));
  CalibrationProblem out = problem;
  out.corners.clear();
  for (auto& share : shares) {
    const std::vector<CornerObservation> corners = share.get();
    out.corners.insert(out.corners.end(), corners.begin(), corners.end());
  }
  out.corners_from = "its " + std::to_string(n) + " saved frames, detected again by " +
                     problem.detector + " through the first pass's camera";
  if (out.corners.empty())
    throw CalibrationInputError(problem.source + ": no layout marker was found again in its " +
                                std::to_string(n) + " saved frames");
  return out;
}

}  // namespace rig::calibrate
