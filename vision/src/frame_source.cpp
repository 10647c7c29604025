#include "vision/frame_source.hpp"

#include <stdexcept>

#include "vision/gige_source.hpp"
#include "vision/replay_source.hpp"
#include "vision/v4l2_source.hpp"

namespace vision {

std::unique_ptr<FrameSource> make_frame_source(const std::string& spec,
                                               const CaptureOptions& options) {
  const auto colon = spec.find(':');
  const std::string scheme = colon == std::string::npos ? "" : spec.substr(0, colon);
  const std::string rest = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (!rest.empty()) {
    if (scheme == "gige") return std::make_unique<GigeSource>(rest, options);
    if (scheme == "v4l2") return std::make_unique<V4l2Source>(rest, options);
    if (scheme == "replay") return std::make_unique<ReplaySource>(rest);
  }
  throw std::invalid_argument("camera spec '" + spec +
                              "': expected gige:ID, gige:ADDRESS, v4l2:/dev/videoN or replay:DIR");
}

}  // namespace vision
