#include "vision/image_codecs.hpp"

#include <dlfcn.h>

namespace vision {
namespace {

// The library's soname (libopencv_imgcodecs.so.406 for OpenCV 4.6), from
// OpenCV's CMake package at build time: a library with another C++ interface
// has another soname, so the names below hold for the library found.
constexpr const char* kCodecLibrary = RIG_OPENCV_IMGCODECS_SONAME;

// The functions, as the library exports them: OpenCV 4's signatures (cv::String
// is std::string), in the Itanium C++ ABI's mangling that g++ and clang use.
using Imread = cv::Mat (*)(const std::string&, int);
using Imwrite = bool (*)(const std::string&, const cv::_InputArray&, const std::vector<int>&);
using Imdecode = cv::Mat (*)(const cv::_InputArray&, int);
using Imencode = bool (*)(const std::string&, const cv::_InputArray&, std::vector<uchar>&,
                          const std::vector<int>&);
// The types are those OpenCV declares, checked without linking a function:
// the static_cast picks the overload of exactly that type or fails to
// compile, and sizeof does not evaluate it.
static_assert(sizeof(static_cast<Imread>(&cv::imread)) > 0);
static_assert(sizeof(static_cast<Imwrite>(&cv::imwrite)) > 0);
static_assert(sizeof(static_cast<Imdecode>(&cv::imdecode)) > 0);
static_assert(sizeof(static_cast<Imencode>(&cv::imencode)) > 0);
constexpr const char* kImread =
    "_ZN2cv6imreadERKNSt7__cxx1112basic_stringIcSt11char_traitsIcESaIcEEEi";
constexpr const char* kImwrite =
    "_ZN2cv7imwriteERKNSt7__cxx1112basic_stringIcSt11char_traitsIcESaIcEEERKNS_11_InputArrayERKSt6"
    "vectorIiSaIiEE";
constexpr const char* kImdecode = "_ZN2cv8imdecodeERKNS_11_InputArrayEi";
constexpr const char* kImencode =
    "_ZN2cv8imencodeERKNSt7__cxx1112basic_stringIcSt11char_traitsIcESaIcEEERKNS_11_InputArrayERSt6"
    "vectorIhSaIhEERKSB_IiSaIiEE";

struct CodecEntryPoints {
  Imread imread = nullptr;
  Imwrite imwrite = nullptr;
  Imdecode imdecode = nullptr;
  Imencode imencode = nullptr;
};

template <typename F>
F codec_entry_point(void* library, const char* name, const char* function) {
  void* address = ::dlsym(library, name);
  if (address == nullptr)
    throw ImageCodecsUnavailable(std::string("image codecs: ") + kCodecLibrary + " has no " +
                                 function + " (" + name + ")");
  return reinterpret_cast<F>(address);
}

// Loads the library (kept for the life of the process) and its entry points.
CodecEntryPoints load_codecs() {
  void* library = ::dlopen(kCodecLibrary, RTLD_NOW | RTLD_LOCAL);
  if (library == nullptr) {
    const char* why = ::dlerror();
    throw ImageCodecsUnavailable(std::string("image codecs: cannot load ") + kCodecLibrary + ": " +
                                 (why != nullptr ? why : "unknown reason") +
                                 " (scripts/setup installs it with OpenCV)");
  }
  CodecEntryPoints c;
  c.imread = codec_entry_point<Imread>(library, kImread, "cv::imread");
  c.imwrite = codec_entry_point<Imwrite>(library, kImwrite, "cv::imwrite");
  c.imdecode = codec_entry_point<Imdecode>(library, kImdecode, "cv::imdecode");
  c.imencode = codec_entry_point<Imencode>(library, kImencode, "cv::imencode");
  return c;
}

// Loaded once, on first use; a failed load throws and is tried again next time.
const CodecEntryPoints& codecs() {
  static const CodecEntryPoints loaded = load_codecs();
  return loaded;
}

}  // namespace

cv::Mat imread(const std::string& path, int flags) {
  return codecs().imread(path, flags);
}

bool imwrite(const std::string& path, cv::InputArray image, const std::vector<int>& params) {
  return codecs().imwrite(path, image, params);
}

cv::Mat imdecode(cv::InputArray bytes, int flags) {
  return codecs().imdecode(bytes, flags);
}

bool imencode(const std::string& extension, cv::InputArray image,
              std::vector<unsigned char>& encoded, const std::vector<int>& params) {
  return codecs().imencode(extension, image, encoded, params);
}

}  // namespace vision
