// sim::camera::CameraServer: a GigE Vision camera on loopback whose every frame is
// what the camera on the simulated bench would see at the moment of exposure.
//
// It is Aravis's in-process GigE Vision simulator (ArvGvFakeCamera: GVCP
// control, GVSP streaming, GenICam features), with its fill callback replaced
// by the scene renderer: for each exposure the callback reads the bench's
// *actual* carriage position (x_mm, y_mm) at its start, waits the exposure
// time as a sensor integrates, reads it again at its end, turns both into
// T_cam_target through the rig geometry and renders the target (with motion
// blur, render_moving, if the carriage moved during the exposure). The
// exposure's start, in seconds since the camera started, is the frame's time
// on the scene's clock (lamp flicker: scene::SensorExposure::start_time_s). Any GigE
// Vision client (vision::GigeSource, arv-tool-0.8, arv-viewer) sees a camera
// "rig-rig-sim-<serial>" (vendor "rig", model "rig-sim", device version
// "realism <profile>") at the interface address.
//
// Its GenICam XML is rig's own (sim/camera/genicam/): CameraServerOptions::
// genicam chooses the SFNC 2.x names (ExposureTime, Gain) or the older ones
// (ExposureTimeAbs, GainRaw); both drive the same registers.
//
// Honoured features: Width, Height, OffsetX, OffsetY (a region of the
// renderer's image; the sensor size is the camera model's), PixelFormat
// (below), ExposureTime or ExposureTimeAbs (exposure duration, blur window,
// electrons collected relative to nominal_exposure_us, dark signal), Gain or
// GainRaw (whole dB, amplifies signal and noise after the well:
// scene::SensorExposure), TriggerMode/TriggerSource=Software/TriggerSoftware,
// AcquisitionStart/Stop, the free run frame rate, GevSCPSPacketSize.
//
// Pixel formats. The renderer's codes (0 .. 255 for an ADC of up to 8 bits,
// 0 .. 2^adc_bits - 1 above: scene::SceneOptions::adc_bits) go on the wire
// full scale onto full scale: value = round(code (2^wire - 1) / (2^adc - 1)),
// exactly the code when the depths agree. Mono8 (an 8-bit sensor's image
// exactly as rendered; a 12-bit sensor's codes rounded to 8 bits), Mono10,
// Mono12, Mono16 (little-endian 16-bit words), Mono12Packed (GigE Vision's
// packing, vision/pixel_format.hpp), BayerRG8: an RGGB mosaic from the
// buffer's first pixel, each pixel the 8-bit value times its filter's
// filter_response (the grey scene seen through a colour filter array; the
// response scales the digitized value, noise included).
//
// Threads: the fill callback runs on Aravis's camera thread, under Aravis's
// fill mutex; the position callback is called there and must be thread-safe
// (sim::bench::BenchServer::actual_position_mm is). Only one GigE camera can bind the
// GVCP port (3956) of an address: one CameraServer per address at a time.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "sim/scene/renderer.hpp"
#include "vision/rig_geometry.hpp"

namespace sim::camera {

// The carriage's actual position (x_mm, y_mm) now. Called from Aravis's
// camera thread: must be thread-safe and quick.
using BenchPositionFn = std::function<std::pair<double, double>()>;

// The true pose of the target in the camera frame with the carriage at
// (x_mm, y_mm), when it is more than the rig geometry's (the carriage's
// pitch and yaw: CarriageAttitude). Called from Aravis's camera thread.
using CameraPoseFn = std::function<vision::Pose(double x_mm, double y_mm)>;

struct CameraServerOptions {
  // IPv4 address (or interface name) the camera binds; loopback by default.
  std::string interface_address = "127.0.0.1";
  // Serial number; the device id is "<vendor>-<model>-<serial>" (< 16 characters).
  std::string serial = "RIGSIM01";
  // How often, in Hz, the camera thread looks for a software trigger: the
  // trigger-to-exposure delay is up to 1 / trigger_poll_hz. Higher = lower
  // latency, more idle wake-ups (1000 Hz: 1 ms, negligible CPU).
  double trigger_poll_hz = 1000;
  // The exposure time (µs) at which a frame is exactly the renderer's output
  // (its SceneOptions::exposure). Other exposures scale the collected
  // electrons linearly (scene::SensorExposure: shot noise as sqrt(signal)).
  double nominal_exposure_us = 10000;
  // Wait the exposure time in the camera thread, so that a moving bench is
  // seen moving (motion blur) and a frame takes as long as a real one. Off
  // renders the position at the start of the exposure only (faster tests).
  bool real_time_exposure = true;
  // Render noise seed: frame k uses seed + k, so a frame can be re-rendered.
  uint64_t seed = 1;
  // Noise draws per position instead: a frame's render seed is seed plus
  // the carriage position at the start of its exposure (whole µm), the
  // same at the same position whatever the frame id. A frame triggered again
  // (an incomplete one on a loaded host) then shifts no later frame's noise,
  // so two runs over the same positions (one pixel format against another)
  // see the same draws. Repeated frames at one position are identical: not
  // for sweeps that average frames.
  bool seed_by_position = false;
  // The GigE Vision bootstrap strings the camera announces itself with
  // (GenICam DeviceVendorName, DeviceModelName, DeviceVersion; < 32
  // characters each): a simulated camera says so, and which realism profile
  // it renders ("realism lab").
  std::string vendor_name = "rig";
  std::string model_name = "rig-sim";
  std::string device_version = "realism ideal";
  // GenICam feature names: "sfnc" (ExposureTime, Gain) or "legacy"
  // (ExposureTimeAbs, GainRaw).
  std::string genicam = "sfnc";
  // A colour sensor: BayerRG8 is the camera's PixelFormat at start (a client
  // may still ask for a Mono format: the grey codes). filter_response: the
  // fraction of the grey level that the R, G and B filters pass (0 .. 1 each),
  // used by BayerRG8 whatever bayer_rg says.
  bool bayer_rg = false;
  std::array<double, 3> filter_response{1.0, 1.0, 1.0};
};

class CameraServer {
 public:
  // The renderer is shared so that tests can render the same scene; the
  // geometry maps bench positions to poses.
  CameraServer(std::shared_ptr<const scene::SceneRenderer> renderer, vision::RigGeometry geometry,
               BenchPositionFn position, CameraServerOptions options = {});
  ~CameraServer();
  CameraServer(const CameraServer&) = delete;
  CameraServer& operator=(const CameraServer&) = delete;

  // Maps carriage positions to poses with `pose` instead of the geometry
  // alone (the carriage's attitude). Call before start().
  void set_pose_model(CameraPoseFn pose) { pose_ = std::move(pose); }

  // Binds the address and starts answering. Throws std::runtime_error naming
  // the address when it cannot bind (another camera there, no such interface).
  void start();
  // Stops answering and releases the address; safe to call twice.
  void stop();

  // "<vendor>-<model>-<serial>" ("rig-rig-sim-RIGSIM01"), as arv-tool-0.8
  // lists it; use it or address() as the gige: spec of a FrameSource.
  std::string device_id() const {
    return options_.vendor_name + "-" + options_.model_name + "-" + options_.serial;
  }
  const std::string& address() const { return options_.interface_address; }

  // What the last frame was rendered from.
  struct Exposure {
    uint64_t frame_id = 0;        // the GigE frame id it was sent with
    double x0_mm = 0, y0_mm = 0;  // carriage at the start of the exposure
    double x1_mm = 0, y1_mm = 0;  // and at its end
    double exposure_us = 0;
    uint64_t seed = 0;  // render seed
  };
  Exposure last_exposure() const;
  uint64_t frames_rendered() const;

 private:
  struct Impl;
  friend struct Impl;
  std::shared_ptr<const scene::SceneRenderer> renderer_;
  vision::RigGeometry geometry_;
  BenchPositionFn position_;
  CameraPoseFn pose_;  // empty: geometry_.T_cam_target
  CameraServerOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::camera
