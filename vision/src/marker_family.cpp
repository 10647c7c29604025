// Marker families: rig's codebook, OpenCV ArUco dictionaries and AprilTag 3
// families as cell grids (see vision/marker_family.hpp).
#include "vision/marker_family.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag36h11.h>

#include <map>
#include <memory>
#include <mutex>
#include <opencv2/aruco.hpp>

#include "vision/codebook.hpp"

namespace vision {

namespace {}  // namespace

MarkerFamily MarkerFamily::from_codebook(const Codebook& codebook) {
  std::vector<uint8_t> white;
  for (const uint16_t code : codebook.codes())
    for (int r = 0; r < kCodeCells; ++r)
      for (int c = 0; c < kCodeCells; ++c)
        white.push_back(Codebook::cell_is_white(code, r, c) ? 1 : 0);
  return MarkerFamily(MarkerFamily::kDefaultName, kCodeCells, 1, std::move(white));
}

namespace {

MarkerFamily from_aruco(const std::string& name, cv::aruco::PREDEFINED_DICTIONARY_NAME which) {
  const cv::Ptr<cv::aruco::Dictionary> dictionary = cv::aruco::getPredefinedDictionary(which);
  const int n = dictionary->markerSize;
  std::vector<uint8_t> white;
  for (int id = 0; id < dictionary->bytesList.rows; ++id) {
    const cv::Mat bits =
        cv::aruco::Dictionary::getBitsFromByteList(dictionary->bytesList.rowRange(id, id + 1), n);
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c)
        white.push_back(bits.at<uint8_t>(r, c) != 0 ? 1 : 0);
  }
  return MarkerFamily(name, n, 1, std::move(white));
}

MarkerFamily from_apriltag(const std::string& name, apriltag_family_t* (*create)(),
                           void (*destroy)(apriltag_family_t*)) {
  std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> family(create(), destroy);
  // The classic families: a one-cell black border, data inside it.
  const int border = 1;
  const int n = family->width_at_border - 2 * border;
  if (family->reversed_border || n <= 0 || family->nbits != static_cast<uint32_t>(n * n)) {
    throw MarkerFamilyError("family " + name + ": layout not supported (" +
                            std::to_string(family->nbits) + " bits)");
  }
  std::vector<uint8_t> white(static_cast<size_t>(family->ncodes) * n * n, 0);
  for (uint32_t id = 0; id < family->ncodes; ++id) {
    const uint64_t code = family->codes[id];
    for (uint32_t i = 0; i < family->nbits; ++i) {
      const int c = static_cast<int>(family->bit_x[i]) - border;
      const int r = static_cast<int>(family->bit_y[i]) - border;
      const bool is_white = ((code >> (family->nbits - 1 - i)) & 1u) != 0;
      white[(static_cast<size_t>(id) * n + r) * n + c] = is_white ? 1 : 0;
    }
  }
  return MarkerFamily(name, n, border, std::move(white));
}

MarkerFamily build(const std::string& name) {
  if (name == MarkerFamily::kDefaultName) return MarkerFamily::from_codebook(Codebook());
  if (name == "aruco:DICT_4X4_50") return from_aruco(name, cv::aruco::DICT_4X4_50);
  if (name == "aruco:DICT_6X6_250") return from_aruco(name, cv::aruco::DICT_6X6_250);
  if (name == "aruco:DICT_APRILTAG_36h11") return from_aruco(name, cv::aruco::DICT_APRILTAG_36h11);
  if (name == "apriltag:tag36h11") return from_apriltag(name, tag36h11_create, tag36h11_destroy);
  if (name == "apriltag:tag16h5") return from_apriltag(name, tag16h5_create, tag16h5_destroy);
  throw MarkerFamilyError("marker family \"" + name + "\": expected one of " +
                          MarkerFamily::names_text());
}

}  // namespace

const std::vector<std::string>& MarkerFamily::names() {
  static const std::vector<std::string> kNames = {kDefaultName,         "aruco:DICT_4X4_50",
                                                  "aruco:DICT_6X6_250", "aruco:DICT_APRILTAG_36h11",
                                                  "apriltag:tag36h11",  "apriltag:tag16h5"};
  return kNames;
}

std::string MarkerFamily::names_text() {
  std::string text;
  for (const std::string& n : names())
    text += (text.empty() ? "\"" : ", \"") + n + "\"";
  return text;
}

const MarkerFamily& MarkerFamily::named(const std::string& name) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<const MarkerFamily>> built;
  const std::lock_guard<std::mutex> lock(mutex);
  auto it = built.find(name);
  if (it == built.end())
    it = built.emplace(name, std::make_unique<const MarkerFamily>(build(name))).first;
  return *it->second;
}

MarkerFamily::MarkerFamily(std::string name, int code_cells, int border_cells,
                           std::vector<uint8_t> white)
    : name_(std::move(name)),
      code_cells_(code_cells),
      border_cells_(border_cells),
      white_(std::move(white)) {
  const size_t per_id = static_cast<size_t>(code_cells) * static_cast<size_t>(code_cells);
  if (code_cells < 1 || border_cells < 1 || white_.size() % per_id != 0) {
    throw std::invalid_argument("MarkerFamily " + name_ + ": " + std::to_string(white_.size()) +
                                " cells for a code grid of " + std::to_string(code_cells) +
                                " and a border of " + std::to_string(border_cells) +
                                "; expected a whole number of code grids, sizes >= 1");
  }
  size_ = static_cast<int>(white_.size() / per_id);
}

void MarkerFamily::check_id(int id) const {
  if (!has_id(id)) {
    throw MarkerFamilyError("marker id " + std::to_string(id) + ": expected an id of " + name_ +
                            " (0 .. " + std::to_string(size_ - 1) + ")");
  }
}

}  // namespace vision
