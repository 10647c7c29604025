#include "sim/camera/server.hpp"

#include <arpa/inet.h>
#include <arv.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "sim/camera/genicam_xml.hpp"
#include "trigger_pacing.hpp"

namespace sim::camera {

namespace {

// GigE Vision 2.0 bootstrap registers (Aravis's ARV_GVBS_*_OFFSET): three
// NUL-terminated strings of 32 bytes each, which the discovery answer and the
// GenICam features DeviceVendorName, DeviceModelName and DeviceVersion read.
constexpr guint32 kManufacturerNameAddress = 0x0048;
constexpr guint32 kModelNameAddress = 0x0068;
constexpr guint32 kDeviceVersionAddress = 0x0088;
constexpr size_t kBootstrapStringBytes = 32;

void write_bootstrap_string(ArvFakeCamera* camera, guint32 address, const std::string& text) {
  char bytes[kBootstrapStringBytes] = {};
  std::memcpy(bytes, text.data(), std::min(text.size(), kBootstrapStringBytes - 1));
  arv_fake_camera_write_memory(camera, address, kBootstrapStringBytes, bytes);
}

// The pixel formats the camera serves (its GenICam XML's PixelFormat
// entries): bits per pixel of the values on the wire; 0 for others.
struct WireFormat {
  int bits = 0;
};

WireFormat wire_format(ArvPixelFormat format) {
  switch (format) {
    case ARV_PIXEL_FORMAT_MONO_8:
    case ARV_PIXEL_FORMAT_BAYER_RG_8:
      return {8};
    case ARV_PIXEL_FORMAT_MONO_10:
      return {10};
    case ARV_PIXEL_FORMAT_MONO_12:
    case ARV_PIXEL_FORMAT_MONO_12_PACKED:
      return {12};
    case ARV_PIXEL_FORMAT_MONO_16:
      return {16};
    default:
      return {};
  }
}

// code -> wire value: full scale onto full scale, round(code (2^wire - 1) /
// (2^source - 1)) (exactly the code when the depths agree; an 8-bit code in
// Mono16 is code x 257), times a colour filter's response.
std::vector<uint16_t> wire_levels(int source_bits, int wire_bits, double response) {
  const double source_max = static_cast<double>((1 << source_bits) - 1);
  const double wire_max = static_cast<double>((1 << wire_bits) - 1);
  std::vector<uint16_t> table(static_cast<size_t>(source_max) + 1);
  for (size_t code = 0; code < table.size(); ++code) {
    const double exact = static_cast<double>(code) * response;
    table[code] = static_cast<uint16_t>(
        source_bits == wire_bits ? std::lround(exact) : std::lround(exact * wire_max / source_max));
  }
  return table;
}

// The values in the format's layout (GigE Vision: little-endian 16-bit words
// for Mono10/12/16; Mono12Packed two pixels in three bytes, B0 = P0[11:4],
// B1 = P1[3:0] << 4 | P0[3:0], B2 = P1[11:4]), at most `capacity` bytes.
void pack(const std::vector<uint16_t>& v, ArvPixelFormat format, int bits, uint8_t* out,
          size_t capacity) {
  std::memset(out, 0, capacity);
  const auto put = [out, capacity](size_t at, unsigned value) {
    if (at < capacity) out[at] = static_cast<uint8_t>(value);
  };
  if (format == ARV_PIXEL_FORMAT_MONO_12_PACKED) {
    for (size_t i = 0, b = 0; i < v.size(); i += 2, b += 3) {
      const unsigned p0 = v[i], p1 = i + 1 < v.size() ? v[i + 1] : 0u;
      put(b, p0 >> 4);
      put(b + 1, (p1 & 0x0Fu) << 4 | (p0 & 0x0Fu));
      put(b + 2, p1 >> 4);
    }
  } else if (bits == 8) {
    for (size_t i = 0; i < v.size(); ++i)
      put(i, v[i]);
  } else {
    for (size_t i = 0; i < v.size(); ++i) {
      put(2 * i, v[i] & 0xFFu);
      put(2 * i + 1, v[i] >> 8u);
    }
  }
}

// The render seed of a carriage position: `seed` plus the position in whole
// µm, x above bit 32 and y below (distinct for positions within 4 km of
// each other). The renderer mixes whatever seed it is given (consecutive
// ones are what the per-frame seeds are), so neighbouring positions draw
// unrelated noise.
uint64_t position_seed(uint64_t seed, double x_mm, double y_mm) {
  const auto um = [](double mm) { return static_cast<uint64_t>(std::llround(mm * 1000)); };
  return seed + (um(x_mm) << 32u) + um(y_mm);
}

}  // namespace

struct CameraServer::Impl {
  CameraServer* server = nullptr;
  ArvGvFakeCamera* gv_camera = nullptr;
  mutable std::mutex mutex;  // guards last
  Exposure last;
  std::atomic<uint64_t> frames{0};
  const std::chrono::steady_clock::time_point epoch = std::chrono::steady_clock::now();

  vision::Pose pose_at(double x_mm, double y_mm) const {
    return server->pose_ ? server->pose_(x_mm, y_mm) : server->geometry_.T_cam_target(x_mm, y_mm);
  }

  // ArvFakeCameraFillPattern: runs on Aravis's camera thread, under its fill mutex.
  static void fill(ArvBuffer* buffer, void* data, guint32 exposure_us, guint32 gain,
                   ArvPixelFormat pixel_format) {
    static_cast<Impl*>(data)->render_into(buffer, exposure_us, gain, pixel_format);
  }

  void render_into(ArvBuffer* buffer, guint32 exposure_us, guint32 gain, ArvPixelFormat format) {
    detail::pace_camera_thread(arv_gv_fake_camera_get_fake_camera(gv_camera));
    const CameraServerOptions& options = server->options_;
    const double start_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - epoch).count();
    const auto [x0, y0] = server->position_();
    double x1 = x0, y1 = y0;
    if (options.real_time_exposure) {
      // A sensor integrates for the exposure time; the carriage keeps moving.
      // Capped so that a silly exposure cannot stall the camera's control channel.
      std::this_thread::sleep_for(
          std::chrono::microseconds(std::min<guint32>(exposure_us, 2000000)));
      std::tie(x1, y1) = server->position_();
    }
    const uint64_t frame_id = arv_buffer_get_frame_id(buffer);
    const uint64_t seed =
        options.seed_by_position ? position_seed(options.seed, x0, y0) : options.seed + frame_id;
    const vision::Pose T0 = pose_at(x0, y0);
    // A carriage that moved less than 1 µm during the exposure is static: the
    // blur would be far below a pixel and render() is several times cheaper.
    const bool moved = std::hypot(x1 - x0, y1 - y0) >= 1e-3;
    // The sensor collects photons for the exposure time (signal and shot
    // noise grow with it, dark signal too); the gain (GainRaw read as dB)
    // amplifies signal and noise alike.
    const scene::SensorExposure sensor{exposure_us / options.nominal_exposure_us,
                                       exposure_us * 1e-6, std::pow(10.0, gain / 20.0), start_s};
    const cv::Mat image =
        moved ? server->renderer_->render_moving(T0, pose_at(x1, y1), seed, sensor).image
              : server->renderer_->render(T0, seed, sensor).image;
    copy_region(buffer, image, format);
    {
      std::lock_guard<std::mutex> lock(mutex);
      last = {frame_id, x0, y0, x1, y1, static_cast<double>(exposure_us), seed};
    }
    frames.fetch_add(1);
  }

  // Writes the buffer's region (Width x Height at OffsetX, OffsetY) of the
  // rendered image in the buffer's pixel format; outside the image is black.
  void copy_region(ArvBuffer* buffer, const cv::Mat& image, ArvPixelFormat format) const {
    const int width = arv_buffer_get_image_width(buffer);
    const int height = arv_buffer_get_image_height(buffer);
    const int x_offset = arv_buffer_get_image_x(buffer);
    const int y_offset = arv_buffer_get_image_y(buffer);
    // Aravis allocated at least width * height * bits per pixel / 8 bytes
    // (arv_fake_camera_get_payload) and checked it before calling us.
    const size_t capacity = static_cast<size_t>(width) * static_cast<size_t>(height) *
                            ARV_PIXEL_FORMAT_BIT_PER_PIXEL(format) / 8;
    auto* out = static_cast<uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, nullptr)));
    const WireFormat wire = wire_format(format);
    if (out == nullptr || width <= 0 || height <= 0 || wire.bits == 0) return;
    // The sensor's codes: 0 .. 255 for an ADC of up to 8 bits, else 0 .. 2^adc_bits - 1.
    const int source_bits = image.depth() == CV_16U ? server->renderer_->options().adc_bits : 8;
    const bool mosaic = format == ARV_PIXEL_FORMAT_BAYER_RG_8;
    const CameraServerOptions& o = server->options_;
    // One table per colour filter (R, G, B); a mono format uses the first.
    std::array<std::vector<uint16_t>, 3> table;
    for (size_t c = 0; c < (mosaic ? 3u : 1u); ++c)
      table[c] = wire_levels(source_bits, wire.bits, mosaic ? o.filter_response[c] : 1.0);
    std::vector<uint16_t> values(static_cast<size_t>(width) * static_cast<size_t>(height), 0);
    const cv::Rect region =
        cv::Rect(x_offset, y_offset, width, height) & cv::Rect(0, 0, image.cols, image.rows);
    for (int y = region.y; y < region.y + region.height; ++y) {
      for (int x = region.x; x < region.x + region.width; ++x) {
        const int code =
            image.depth() == CV_16U ? image.at<uint16_t>(y, x) : image.at<uint8_t>(y, x);
        // RGGB from the buffer's first pixel: R on even rows and columns, B on odd ones.
        const int rx = x - x_offset, ry = y - y_offset;
        const size_t filter =
            !mosaic ? 0 : (ry % 2 == 0 ? (rx % 2 == 0 ? 0 : 1) : (rx % 2 == 0 ? 1 : 2));
        values[static_cast<size_t>(ry) * width + rx] = table[filter][static_cast<size_t>(code)];
      }
    }
    pack(values, format, wire.bits, out, capacity);
  }
};

CameraServer::CameraServer(std::shared_ptr<const scene::SceneRenderer> renderer,
                           vision::RigGeometry geometry, BenchPositionFn position,
                           CameraServerOptions options)
    : renderer_(std::move(renderer)),
      geometry_(std::move(geometry)),
      position_(std::move(position)),
      options_(std::move(options)) {
  if (!renderer_ || !position_)
    throw std::invalid_argument("sim::camera::CameraServer: renderer and position are required");
  if (!(options_.trigger_poll_hz > 0) || !(options_.nominal_exposure_us > 0))
    throw std::invalid_argument(
        "sim::camera::CameraServer: trigger_poll_hz and nominal_exposure_us must be > 0");
  if (options_.genicam != "sfnc" && options_.genicam != "legacy")
    throw std::invalid_argument("sim::camera::CameraServer: genicam \"" + options_.genicam +
                                "\": expected \"sfnc\" or \"legacy\"");
  for (double r : options_.filter_response)
    if (!(r >= 0 && r <= 1))
      throw std::invalid_argument(
          "sim::camera::CameraServer: filter_response values must be within 0 .. 1");
  if (options_.serial.empty() || options_.serial.size() >= 16)
    throw std::invalid_argument("sim::camera::CameraServer: serial '" + options_.serial +
                                "' must have 1 to 15 characters");
  for (const std::string* text :
       {&options_.vendor_name, &options_.model_name, &options_.device_version}) {
    if (text->empty() || text->size() >= kBootstrapStringBytes)
      throw std::invalid_argument(
          "sim::camera::CameraServer: '" + *text +
          "' must have 1 to 31 characters (a GigE Vision bootstrap string)");
  }
}

CameraServer::~CameraServer() {
  stop();
}

namespace {

// The IPv4 addresses and the names of this machine's network interfaces, for
// telling an address on no interface from a port another camera holds.
std::vector<std::string> interface_addresses_and_names() {
  std::vector<std::string> found;
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return found;
  for (const ifaddrs* i = list; i != nullptr; i = i->ifa_next) {
    if (i->ifa_name != nullptr) found.emplace_back(i->ifa_name);
    if (i->ifa_addr == nullptr || i->ifa_addr->sa_family != AF_INET) continue;
    char text[INET_ADDRSTRLEN] = {};
    const auto* a = reinterpret_cast<const sockaddr_in*>(i->ifa_addr);
    if (inet_ntop(AF_INET, &a->sin_addr, text, sizeof text)) found.emplace_back(text);
  }
  freeifaddrs(list);
  return found;
}

std::string ipv4_addresses_of(const std::vector<std::string>& found) {
  std::string listed;
  for (const std::string& f : found) {
    in_addr ignored{};
    if (inet_pton(AF_INET, f.c_str(), &ignored) == 1) listed += (listed.empty() ? "" : ", ") + f;
  }
  return listed;
}

// The camera's GenICam XML in a file of its own for as long as Aravis reads
// it (arv_gv_fake_camera_new_full reads the file whole, then it is removed).
class GenicamFile {
 public:
  explicit GenicamFile(const char* xml) {
    const std::string pattern =
        (std::filesystem::temp_directory_path() / "rig-sim-genicam-XXXXXX").string();
    std::vector<char> name(pattern.begin(), pattern.end());
    name.push_back('\0');
    const int fd = mkstemp(name.data());
    if (fd < 0)
      throw std::runtime_error("sim camera: cannot write its GenICam file " + pattern + ": " +
                               std::strerror(errno));
    const size_t size = std::strlen(xml);
    const bool written = write(fd, xml, size) == static_cast<ssize_t>(size);
    ::close(fd);
    path_ = name.data();
    if (!written) {
      unlink(path_.c_str());
      throw std::runtime_error("sim camera: cannot write its GenICam file " + path_);
    }
  }
  ~GenicamFile() { unlink(path_.c_str()); }
  GenicamFile(const GenicamFile&) = delete;
  GenicamFile& operator=(const GenicamFile&) = delete;
  const char* path() const { return path_.c_str(); }

 private:
  std::string path_;
};

// Throws when `address` is neither an address nor a name of an interface
// (Aravis serves GigE Vision only on an interface's own address), or when
// another camera holds its control port 3956.
void check_camera_address(const std::string& address) {
  const std::vector<std::string> found = interface_addresses_and_names();
  if (std::find(found.begin(), found.end(), address) == found.end()) {
    throw std::runtime_error(
        "sim camera: camera.address \"" + address +
        "\" is not the address (or name) of a network interface of this machine; it has " +
        ipv4_addresses_of(found) +
        " (ip -brief addr). Use one of them, or add the address to an interface first: `sudo ip "
        "addr add " +
        address + (address.rfind("127.", 0) == 0 ? "/8 dev lo`" : "/24 dev INTERFACE`"));
  }
  // Aravis binds the control port with address reuse and starts even when it
  // fails; a plain bind first tells that another camera holds the address.
  in_addr ip{};
  if (inet_pton(AF_INET, address.c_str(), &ip) != 1) return;
  const int probe = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(3956);  // GVCP, GigE Vision's control port
  sa.sin_addr = ip;
  const bool taken = probe >= 0 && bind(probe, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0 &&
                     errno == EADDRINUSE;
  if (probe >= 0) close(probe);
  if (taken) {
    throw std::runtime_error(
        "sim camera: GigE Vision control port " + address +
        ":3956 is taken: another camera serves there, most likely another `rig sim` (stop it, "
        "or find it with `ss -ulpn 'sport = :3956'`), or give this one another camera.address, "
        "e.g. 127.0.0.2 after `sudo ip addr add 127.0.0.2/8 dev lo`");
  }
}

}  // namespace

void CameraServer::start() {
  if (impl_) return;
  check_camera_address(options_.interface_address);
  auto impl = std::make_unique<Impl>();
  impl->server = this;
  impl->gv_camera = arv_gv_fake_camera_new_full(
      options_.interface_address.c_str(), options_.serial.c_str(),
      GenicamFile(options_.genicam == "legacy" ? kGenicamLegacyXml : kGenicamSfncXml).path());
  if (impl->gv_camera == nullptr || !arv_gv_fake_camera_is_running(impl->gv_camera)) {
    if (impl->gv_camera != nullptr) g_object_unref(impl->gv_camera);
    throw std::runtime_error("sim camera: Aravis cannot serve GigE Vision on '" +
                             options_.interface_address +
                             "' (its port 3956 was free and the address is an interface's)");
  }
  ArvFakeCamera* camera = arv_gv_fake_camera_get_fake_camera(impl->gv_camera);
  const vision::Camera& model = renderer_->camera();
  const auto w = static_cast<guint32>(model.width_px()),
             h = static_cast<guint32>(model.height_px());
  arv_fake_camera_write_register(camera, ARV_FAKE_CAMERA_REGISTER_SENSOR_WIDTH, w);
  arv_fake_camera_write_register(camera, ARV_FAKE_CAMERA_REGISTER_SENSOR_HEIGHT, h);
  arv_fake_camera_write_register(camera, ARV_FAKE_CAMERA_REGISTER_WIDTH, w);
  arv_fake_camera_write_register(camera, ARV_FAKE_CAMERA_REGISTER_HEIGHT, h);
  arv_fake_camera_write_register(camera, ARV_FAKE_CAMERA_REGISTER_EXPOSURE_TIME_US,
                                 static_cast<guint32>(std::lround(options_.nominal_exposure_us)));
  arv_fake_camera_set_trigger_frequency(camera, options_.trigger_poll_hz);
  write_bootstrap_string(camera, kManufacturerNameAddress, options_.vendor_name);
  write_bootstrap_string(camera, kModelNameAddress, options_.model_name);
  write_bootstrap_string(camera, kDeviceVersionAddress, options_.device_version);
  if (options_.bayer_rg)
    arv_fake_camera_write_register(camera, ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT,
                                   ARV_PIXEL_FORMAT_BAYER_RG_8);
  arv_fake_camera_set_fill_pattern(camera, &Impl::fill, impl.get());
  impl_ = std::move(impl);
}

void CameraServer::stop() {
  if (!impl_) return;
  g_object_unref(impl_->gv_camera);  // joins Aravis's camera thread: no fill runs after this
  impl_.reset();
}

CameraServer::Exposure CameraServer::last_exposure() const {
  if (!impl_) return {};
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->last;
}

uint64_t CameraServer::frames_rendered() const {
  return impl_ ? impl_->frames.load() : 0;
}

}  // namespace sim::camera
