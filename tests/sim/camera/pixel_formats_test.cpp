// The simulated camera's pixel formats and GenICam feature variants through
// the real capture path (vision::GigeSource on loopback, GVSP packets, the
// conversions of vision/pixel_format.hpp). Every frame's render seed is
// known (CameraServer::last_exposure), so the expected image is the
// renderer's own output for that seed, carried through the format by the
// rule the camera documents (sim/camera/server.hpp): the comparisons are
// exact. One GigE camera per address: RESOURCE_LOCK gige_loopback.
#include <arv.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "camera_frames.hpp"
#include "sim/camera/server.hpp"
#include "vision/frame_measurement.hpp"
#include "vision/gige_source.hpp"
#include "vision/pixel_format.hpp"

namespace {

using rig_test::differing_pixels;
using rig_test::kFrameWait;

using namespace std::chrono_literals;

constexpr double kX = 250, kY = 150;  // bench position of every frame, mm

class PixelFormats : public ::testing::Test {
 protected:
  PixelFormats()
      : geometry_(
            vision::RigGeometry::load(std::string(RIG_SOURCE_DIR) + "/config/rigs/sim.toml")) {}

  // A camera whose sensor has an ADC of `adc_bits` (SceneOptions::adc_bits).
  void start(int adc_bits, sim::camera::CameraServerOptions options = {},
             sim::scene::SceneOptions scene = {}) {
    scene.adc_bits = adc_bits;
    renderer_ = std::make_shared<sim::scene::SceneRenderer>(vision::Camera::paper_default(),
                                                            vision::Target::paper_default(),
                                                            vision::Codebook(), scene);
    options.real_time_exposure = false;
    server_ = std::make_unique<sim::camera::CameraServer>(
        renderer_, geometry_,
        [this] {
          std::lock_guard<std::mutex> lock(mutex_);
          return position_;
        },
        options);
    server_->start();
  }
  // One triggered frame in `pixel_format`. A payload the format gets wrong
  // makes every frame incomplete, and grab() throws once its retries are
  // spent. A single incomplete frame is a packet lost on a busy host (seen
  // with sanitized tests on both cores), which the retry rides out, so the
  // count of incomplete frames is not held to zero here; the capture tests
  // hold the link itself to that.
  vision::Frame grab(const std::string& pixel_format, vision::CaptureOptions options = {}) {
    options.pixel_format = pixel_format;
    vision::GigeSource source(server_->address(), options);
    source.open();
    source.trigger();
    return source.grab(kFrameWait);
  }
  // The sensor's codes of the last frame.
  cv::Mat rendered(double exposure_scale = 1.0, double gain = 1.0) const {
    const auto e = server_->last_exposure();
    return renderer_
        ->render(geometry_.T_cam_target(e.x0_mm, e.y0_mm), e.seed,
                 sim::scene::SensorExposure{exposure_scale, e.exposure_us * 1e-6, gain})
        .image;
  }

  vision::RigGeometry geometry_;
  std::shared_ptr<sim::scene::SceneRenderer> renderer_;
  std::unique_ptr<sim::camera::CameraServer> server_;
  // The bench's actual position: set by the test thread between frames,
  // read on the camera thread during one (after trigger()).
  void move_to(double x_mm, double y_mm) {
    std::lock_guard<std::mutex> lock(mutex_);
    position_ = {x_mm, y_mm};
  }
  std::mutex mutex_;
  std::pair<double, double> position_{kX, kY};
};

// Full scale onto full scale: round(code (2^to - 1) / (2^from - 1)),
// computed here independently of the camera's table.
cv::Mat rescaled(const cv::Mat& codes, int from_bits, int to_bits) {
  cv::Mat wide;
  codes.convertTo(wide, CV_64F);
  const double scale = ((1 << to_bits) - 1.0) / ((1 << from_bits) - 1.0);
  cv::Mat out(codes.size(), to_bits > 8 ? CV_16UC1 : CV_8UC1);
  for (int y = 0; y < codes.rows; ++y)
    for (int x = 0; x < codes.cols; ++x) {
      const long v = std::lround(wide.at<double>(y, x) * scale);
      if (to_bits > 8)
        out.at<uint16_t>(y, x) = static_cast<uint16_t>(v);
      else
        out.at<uint8_t>(y, x) = static_cast<uint8_t>(v);
    }
  return out;
}

struct FormatCase {
  int adc_bits;
  const char* pixel_format;
  int wire_bits;  // the format's depth; the frame holds the codes rescaled to it
};

class PixelFormatOnTheWire : public PixelFormats,
                             public ::testing::WithParamInterface<FormatCase> {};

TEST_P(PixelFormatOnTheWire, FrameHoldsTheSensorsCodesAtTheFormatsDepth) {
  const FormatCase c = GetParam();
  start(c.adc_bits);
  const vision::Frame frame = grab(c.pixel_format);
  const cv::Mat codes = rendered();
  ASSERT_EQ(codes.depth(), c.adc_bits > 8 ? CV_16U : CV_8U);
  const int code_bits = std::max(c.adc_bits, 8);  // up to 8 bits: codes on the 0..255 scale
  const cv::Mat expected =
      code_bits == c.wire_bits ? codes : rescaled(codes, code_bits, c.wire_bits);
  EXPECT_EQ(differing_pixels(frame.image, expected), 0);
  EXPECT_EQ(frame.significant_bits, c.wire_bits);
  // The frame is no blank: the target's paper and ink both reach the wire.
  double lo = 0, hi = 0;
  cv::minMaxLoc(frame.image, &lo, &hi);
  EXPECT_GT(hi - lo, 0.5 * ((1 << c.wire_bits) - 1));
}

INSTANTIATE_TEST_SUITE_P(
    Formats, PixelFormatOnTheWire,
    ::testing::Values(FormatCase{8, "Mono8", 8}, FormatCase{8, "Mono10", 10},
                      FormatCase{8, "Mono12", 12}, FormatCase{8, "Mono12Packed", 12},
                      FormatCase{10, "Mono10", 10}, FormatCase{10, "Mono8", 8},
                      FormatCase{12, "Mono12", 12}, FormatCase{12, "Mono12Packed", 12},
                      FormatCase{12, "Mono8", 8}, FormatCase{12, "Mono16", 16}),
    [](const ::testing::TestParamInfo<FormatCase>& info) {
      return "Adc" + std::to_string(info.param.adc_bits) + "_" + info.param.pixel_format;
    });

// BayerRG8: the camera's RGGB mosaic of the grey codes, each pixel times its
// filter's response, demosaiced by the capture path. The mosaic is built
// here from the rendered codes; the capture path must then return exactly
// OpenCV's luminance of it (RGGB = OpenCV's BayerBG; vision/pixel_format.hpp).
TEST_F(PixelFormats, BayerRG8IsTheFilteredMosaicDemosaicedToLuminance) {
  sim::camera::CameraServerOptions options;
  options.bayer_rg = true;
  options.filter_response = {0.5, 1.0, 0.25};
  start(8, options);
  const vision::Frame frame = grab("BayerRG8");
  const cv::Mat codes = rendered();
  cv::Mat mosaic(codes.size(), CV_8UC1);
  for (int y = 0; y < codes.rows; ++y)
    for (int x = 0; x < codes.cols; ++x) {
      const double response = y % 2 == 0 ? (x % 2 == 0 ? 0.5 : 1.0) : (x % 2 == 0 ? 1.0 : 0.25);
      mosaic.at<uint8_t>(y, x) =
          static_cast<uint8_t>(std::lround(codes.at<uint8_t>(y, x) * response));
    }
  cv::Mat luminance;
  cv::cvtColor(mosaic, luminance, cv::COLOR_BayerBG2GRAY);
  EXPECT_EQ(differing_pixels(frame.image, luminance), 0);
  // The filters dim the image: paper (~195 DN grey) comes out near
  // 0.299 * 0.5 + 0.587 + 0.114 * 0.25 = 0.77 of its grey level.
  EXPECT_LT(cv::mean(frame.image)[0], 0.85 * cv::mean(codes)[0]);
}

// A colour sensor starts in BayerRG8: a client that keeps the camera's
// pixel format gets the mosaic.
TEST_F(PixelFormats, ColourSensorStartsInBayerRG8) {
  sim::camera::CameraServerOptions options;
  options.bayer_rg = true;
  start(8, options);
  GError* error = nullptr;
  ArvCamera* camera = arv_camera_new(server_->address().c_str(), &error);
  ASSERT_NE(camera, nullptr) << (error ? error->message : "");
  EXPECT_STREQ(arv_camera_get_pixel_format_as_string(camera, nullptr), "BayerRG8");
  g_object_unref(camera);
}

// The older (SFNC 1.x) and the current (SFNC 2.x) feature names: the capture
// path sets the exposure and the gain with whichever the camera has, and the
// camera's frame is then the render of that exposure (half the nominal 10 ms:
// half the electrons) amplified by 6 dB.
class GenicamNames : public PixelFormats, public ::testing::WithParamInterface<const char*> {};

TEST_P(GenicamNames, ExposureAndTriggerWorkWithTheCamerasNames) {
  const std::string names = GetParam();
  sim::camera::CameraServerOptions options;
  options.genicam = names;
  start(8, options);
  {
    GError* error = nullptr;
    ArvCamera* camera = arv_camera_new(server_->address().c_str(), &error);
    ASSERT_NE(camera, nullptr) << (error ? error->message : "");
    const bool sfnc = names == "sfnc";
    EXPECT_EQ(arv_camera_is_feature_available(camera, "ExposureTime", nullptr), sfnc);
    EXPECT_EQ(arv_camera_is_feature_available(camera, "ExposureTimeAbs", nullptr), !sfnc);
    EXPECT_EQ(arv_camera_is_feature_available(camera, "Gain", nullptr), sfnc);
    EXPECT_EQ(arv_camera_is_feature_available(camera, "GainRaw", nullptr), !sfnc);
    g_object_unref(camera);
  }
  vision::CaptureOptions capture;
  capture.exposure_us = 5000;
  capture.gain = 6;  // dB: Gain (float) or GainRaw (integer), both whole dB here
  const vision::Frame frame = grab("Mono8", capture);
  EXPECT_EQ(server_->last_exposure().exposure_us, 5000);
  EXPECT_EQ(server_->last_exposure().frame_id, frame.frame_id);
  EXPECT_EQ(differing_pixels(frame.image, rendered(0.5, std::pow(10.0, 6 / 20.0))), 0);
}

INSTANTIATE_TEST_SUITE_P(Names, GenicamNames, ::testing::Values("sfnc", "legacy"));

// Packet size and inter-packet delay from the capture options reach the
// camera's registers (read back by a second GigE Vision client: reads need
// no control), and the frame still arrives whole in packets of that size.
// The simulated camera stamps frames with the host's own wall clock
// (Aravis's fake camera: g_get_real_time at the start of the exposure), so
// the true offset is 0 and the arrival method's offset is the smallest
// exposure + render + transfer time seen: positive, and under the 10 s a
// frame may take. The mapped exposure start precedes the frame's arrival.
TEST_F(PixelFormats, CameraTimestampsMapToHostTimeByArrival) {
  start(8);
  vision::GigeSource source(server_->address());
  source.open();
  for (int k = 0; k < 3; ++k) {
    source.trigger();
    const vision::Frame frame = source.grab(kFrameWait);
    ASSERT_TRUE(frame.exposure_host_time.has_value());
    EXPECT_LE(*frame.exposure_host_time, frame.host_time);
  }
  const vision::CameraClock& clock = source.camera_clock();
  EXPECT_EQ(clock.method(), vision::CameraClock::Method::kArrival);  // no latch in its XML
  EXPECT_GT(clock.offset_ns(), 0);
  EXPECT_LT(clock.offset_ns(), 10'000'000'000);
  RecordProperty("arrival_offset_ms", std::to_string(clock.offset_ns() * 1e-6));
}

TEST_F(PixelFormats, PacketSizeAndInterPacketDelayAreSet) {
  start(8);
  vision::CaptureOptions options;
  options.pixel_format = "Mono8";
  options.packet_size_bytes = 1400;
  options.inter_packet_delay_ns = 2000;
  vision::GigeSource source(server_->address(), options);
  source.open();
  GError* error = nullptr;
  ArvCamera* reader = arv_camera_new(server_->address().c_str(), &error);
  ASSERT_NE(reader, nullptr) << (error ? error->message : "");
  EXPECT_EQ(arv_camera_gv_get_packet_size(reader, nullptr), 1400u);
  // The fake camera's timestamp ticks are ns (tick frequency 1 GHz): GevSCPD = the delay.
  EXPECT_EQ(arv_device_get_integer_feature_value(arv_camera_get_device(reader), "GevSCPD", nullptr),
            2000);
  g_object_unref(reader);
  source.trigger();
  const vision::Frame frame = source.grab(kFrameWait);
  EXPECT_EQ(differing_pixels(frame.image, rendered()), 0);
  // An incomplete frame (a datagram dropped on a loaded host: the fake
  // camera does not resend) is triggered again, never delivered: the one
  // frame delivered is the render checked above.
  EXPECT_EQ(source.counters().delivered, 1u);
}

// What a sweep over the distance range sees through each format: a lab
// sensor (10500 e- full well, 3 e- read noise: sim::camera's "lab" profile)
// read by an 8-bit ADC in Mono8 and by a 12-bit ADC in Mono12, the same
// electrons and noise draws at every bench position, detected and solved by
// the rig's own pipeline (vision::FrameMeasurer). 8-bit quantization adds
// 41 e- / sqrt(12) = 12 e- RMS to every pixel, 60 % of the shot noise on the
// ink (420 e-: 20 e-): the 12-bit frames must find at least the markers the
// 8-bit ones find, with corners no worse. The camera draws its noise per
// position (CameraServerOptions::seed_by_position), so a frame triggered
// again after a datagram lost on a loaded host changes no draw (the seeds of
// the frames measured are held equal) and the test is deterministic; the 2 %
// margin on the corner RMS allows for the sign of the quantization's effect
// on one set of draws (the figures are test properties; measured: 19 and 19
// markers, corner RMS 0.0096 px Mono8, 0.0095 px Mono12). The distance RMS
// over every solver is recorded, not asserted: at ~0.01 mm it is set by the
// solvers and the 6 views, not by the ADC (measured 0.0128 mm Mono8,
// 0.0149 mm Mono12).
struct SweepQuality {
  int markers = 0;              // detections whose id is a target marker in view
  double corner_rms_px = 0;     // against the renderer's ground truth
  double distance_rms_mm = 0;   // every converged target-scope estimate against |t|
  std::vector<uint64_t> seeds;  // render seed of each position's frame
};

class FormatSweep : public PixelFormats {
 protected:
  SweepQuality sweep(int adc_bits, const char* pixel_format) {
    sim::scene::SceneOptions scene;
    scene.full_well_electrons = 10500;
    scene.read_noise_electrons = 3;
    scene.exposure = 0.8;
    sim::camera::CameraServerOptions camera;
    camera.seed_by_position = true;
    start(adc_bits, camera, scene);
    const vision::FrameMeasurer measurer(vision::Camera::paper_default(),
                                         vision::Target::paper_default());
    vision::CaptureOptions options;
    options.pixel_format = pixel_format;
    vision::GigeSource source(server_->address(), options);
    source.open();
    SweepQuality q;
    double corner_sq = 0, distance_sq = 0;
    int corners = 0, distances = 0;
    for (const double x : {100.0, 250.0, 400.0, 550.0, 700.0, 850.0}) {
      move_to(x, kY);
      source.trigger();
      const vision::Frame frame = source.grab(kFrameWait);
      q.seeds.push_back(server_->last_exposure().seed);
      const vision::Pose T = geometry_.T_cam_target(x, kY);
      const auto truth = renderer_->ground_truth(T);
      const vision::FrameMeasurement m = measurer.measure(frame.image);
      for (const vision::Detection& d : m.primary().detections) {
        for (const auto& t : truth) {
          if (t.id != d.id) continue;
          ++q.markers;
          for (int k = 0; k < 4; ++k) {
            corner_sq +=
                (d.corners_px[static_cast<size_t>(k)] - t.corners_px[static_cast<size_t>(k)])
                    .squaredNorm();
            ++corners;
          }
        }
      }
      for (const vision::ScopeEstimate& e : m.primary().estimates) {
        if (e.scope != "target" || !e.estimate.converged) continue;
        const double error_mm = (e.estimate.distance_m - T.t.norm()) * 1000;
        distance_sq += error_mm * error_mm;
        ++distances;
      }
    }
    server_->stop();
    q.corner_rms_px = corners > 0 ? std::sqrt(corner_sq / corners) : 1e9;
    q.distance_rms_mm = distances > 0 ? std::sqrt(distance_sq / distances) : 1e9;
    return q;
  }
};

TEST_F(FormatSweep, Mono12FromA12BitSensorIsAtLeastAsGoodAsMono8) {
  const SweepQuality mono8 = sweep(8, "Mono8");
  const SweepQuality mono12 = sweep(12, "Mono12");
  RecordProperty("mono8_markers", mono8.markers);
  RecordProperty("mono12_markers", mono12.markers);
  RecordProperty("mono8_corner_rms_px", std::to_string(mono8.corner_rms_px));
  RecordProperty("mono12_corner_rms_px", std::to_string(mono12.corner_rms_px));
  RecordProperty("mono8_distance_rms_mm", std::to_string(mono8.distance_rms_mm));
  RecordProperty("mono12_distance_rms_mm", std::to_string(mono12.distance_rms_mm));
  ASSERT_EQ(mono12.seeds, mono8.seeds);
  ASSERT_GT(mono8.markers, 0);
  EXPECT_GE(mono12.markers, mono8.markers);
  EXPECT_LE(mono12.corner_rms_px, mono8.corner_rms_px * 1.02);
}

}  // namespace
