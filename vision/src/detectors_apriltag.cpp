// AprilTag 3 (libapriltag) in the detector registry (vision/detectors.hpp).
// Krogius, Haggenmiller & Olson 2019, DOI 10.1109/IROS40897.2019.8967787.
#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag36h11.h>

#include <mutex>

#include "detectors_internal.hpp"
#include "vision/codebook.hpp"
#include "vision/marker_family.hpp"

namespace vision::detectors_internal {
namespace {

// The libapriltag family a detector decodes: one of the library's own, or
// rig's codebook as a 16-bit family. AprilTag turns a code by a quarter by
// rotating its bit string by nbits / 4, so the bits must be read in an order
// whose groups of four are one cell and its three quarter turns: tag16h5's
// order (bit_x, bit_y on the 6-cell grid with its border), which rig4x4's
// 4x4 code inside a one-cell border shares.
// 16-bit families (tag16h5, rig4x4; minimum Hamming distance 5) are decoded
// without correction. AprilTag has none of rig's border and quiet-zone
// checks, so its code check is all that tells a quad from clutter (the code
// cells themselves make quads): with b bits corrected a random quad decodes
// with probability 4 n sum_{k<=b} C(16, k) / 2^16, for tag16h5 (n = 30)
// 0.18 % at b = 0, 3.1 % at 1, 25 % at 2 (libapriltag's default). tag36h11
// keeps that default of 2 bits: 4 x 587 x 667 / 2^36 = 2.3e-5.
class Family {
 public:
  explicit Family(const std::string& name) {
    if (name == "apriltag:tag36h11" || name == "aruco:DICT_APRILTAG_36h11") {
      own(tag36h11_create(), tag36h11_destroy);
      correction_bits_ = 2;  // libapriltag's default (apriltag_detector_add_family)
    } else if (name == "apriltag:tag16h5") {
      own(tag16h5_create(), tag16h5_destroy);
      correction_bits_ = 0;  // see the class comment
    } else {
      build_rig();
    }
  }
  ~Family() {
    if (destroy_) destroy_(library_);
  }
  Family(const Family&) = delete;
  Family& operator=(const Family&) = delete;

  apriltag_family_t* get() { return library_ ? library_ : &custom_; }
  int correction_bits() const { return correction_bits_; }

 private:
  void own(apriltag_family_t* family, void (*destroy)(apriltag_family_t*)) {
    library_ = family;
    destroy_ = destroy;
  }

  void build_rig() {
    std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> order(tag16h5_create(),
                                                                           tag16h5_destroy);
    bit_x_.assign(order->bit_x, order->bit_x + order->nbits);
    bit_y_.assign(order->bit_y, order->bit_y + order->nbits);
    const MarkerFamily& rig = MarkerFamily::named(MarkerFamily::kDefaultName);
    for (int id = 0; id < rig.size(); ++id) {
      uint64_t code = 0;  // the first cell read is the most significant bit
      for (size_t i = 0; i < bit_x_.size(); ++i)
        if (rig.cell_is_white(id, static_cast<int>(bit_y_[i]), static_cast<int>(bit_x_[i])))
          code |= uint64_t{1} << (bit_x_.size() - 1 - i);
      codes_.push_back(code);
    }
    const Codebook codebook;
    custom_.ncodes = static_cast<uint32_t>(codes_.size());
    custom_.codes = codes_.data();
    custom_.width_at_border = order->width_at_border;
    custom_.total_width = order->total_width;
    custom_.reversed_border = false;
    custom_.nbits = static_cast<uint32_t>(bit_x_.size());
    custom_.bit_x = bit_x_.data();
    custom_.bit_y = bit_y_.data();
    custom_.h = static_cast<uint32_t>(codebook.options().min_hamming_distance);
    custom_.name = name_.data();
    correction_bits_ = 0;  // see the class comment
  }

  apriltag_family_t* library_ = nullptr;
  void (*destroy_)(apriltag_family_t*) = nullptr;
  apriltag_family_t custom_{};
  std::vector<uint64_t> codes_;
  std::vector<uint32_t> bit_x_, bit_y_;
  std::string name_ = "rig4x4";
  int correction_bits_ = 1;
};

class AprilTagDetector : public FiducialDetector {
 public:
  AprilTagDetector(int decimation, const std::string& family)
      : name_("apriltag:d" + std::to_string(decimation)),
        family_name_(family),
        family_(family),
        decimation_(decimation),
        // OpenCV's DICT_APRILTAG_36h11 is tag36h11 turned by 180 degrees,
        // same ids: its printed A is libapriltag's bottom-right, p[1].
        first_corner_(family == "aruco:DICT_APRILTAG_36h11" ? 2 : 0) {
    release(create());  // builds the family's decode table once
  }
  // Every detector is idle by now. Destroying a detector frees the
  // family's decode table (apriltag_detector_clear_families); the first
  // does, the others find it gone.
  ~AprilTagDetector() override {
    for (apriltag_detector_t* td : idle_)
      apriltag_detector_destroy(td);
  }
  const std::string& name() const override { return name_; }
  const std::string& family() const override { return family_name_; }

  std::vector<Detection> detect(const cv::Mat& image) const override {
    cv::Mat gray = to_gray8(image);
    std::vector<Detection> detections;
    if (gray.empty()) return detections;
    if (!gray.isContinuous() && gray.data == image.data) gray = gray.clone();
    image_u8_t im{gray.cols, gray.rows, static_cast<int32_t>(gray.step[0]), gray.ptr<uint8_t>()};
    apriltag_detector_t* td = acquire();
    zarray_t* found = apriltag_detector_detect(td, &im);  // reads im, does not write it
    release(td);
    for (int k = 0; k < zarray_size(found); ++k) {
      apriltag_detection_t* det = nullptr;
      zarray_get(found, k, &det);
      Detection d;
      d.id = det->id;
      // p[0..3] are the printed bottom-left, bottom-right, top-right,
      // top-left, with pixel centres at +0.5 (vision/detectors.hpp).
      for (int j = 0; j < 4; ++j) {
        const double* p = det->p[(3 - j + 4 - first_corner_) % 4];
        d.corners_px[static_cast<size_t>(j)] = Eigen::Vector2d(p[0] - 0.5, p[1] - 0.5);
      }
      d.rotation = quarter_turns_of(d.corners_px);
      d.quality.bits_corrected = det->hamming;
      detections.push_back(d);
    }
    apriltag_detections_destroy(found);
    sort_detections(detections);
    return detections;
  }

 private:
  apriltag_detector_t* create() const {
    apriltag_detector_t* td = apriltag_detector_create();
    td->quad_decimate = static_cast<float>(decimation_);
    td->nthreads = 1;  // a sweep measures whole frames in parallel instead
    apriltag_detector_add_family_bits(td, family_.get(), family_.correction_bits());
    return td;
  }
  apriltag_detector_t* acquire() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (idle_.empty()) return create();  // under the lock: add_family reads the table's state
    apriltag_detector_t* td = idle_.back();
    idle_.pop_back();
    return td;
  }
  void release(apriltag_detector_t* td) const {
    const std::lock_guard<std::mutex> lock(mutex_);
    idle_.push_back(td);
  }

  std::string name_;
  std::string family_name_;
  mutable Family family_;
  int decimation_;
  int first_corner_;  // quarter turns from libapriltag's top-left to the printed A
  mutable std::mutex mutex_;
  mutable std::vector<apriltag_detector_t*> idle_;
};

}  // namespace

std::unique_ptr<FiducialDetector> make_apriltag_detector(int decimation,
                                                         const std::string& family) {
  return std::make_unique<AprilTagDetector>(decimation, family);
}

}  // namespace vision::detectors_internal
