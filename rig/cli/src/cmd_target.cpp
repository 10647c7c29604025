// rig target: a whole target sheet (A4 or A3) from a layout file, to print.
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "vision/artwork.hpp"
#include "vision/codebook.hpp"
#include "vision/target.hpp"

namespace rig::cli {

void add_target_command(CLI::App& app, ExitStatus& status) {
  auto* cmd = app.add_subcommand(
      "target", "Write a target sheet at true physical size as SVG, PDF or PNG (by extension)");
  auto layout = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto options = std::make_shared<vision::TargetArtworkOptions>();
  auto no_label = std::make_shared<bool>(false);
  cmd->add_option("--target", *layout,
                  "layout file (TOML: paper, origin_mm, pose_marker, [[markers]] id, side_mm, "
                  "centre_mm), e.g. config/targets/paper.toml")
      ->required();
  cmd->add_option("--out", *out, "output file: .svg, .pdf or .png")->required();
  cmd->add_option("--dpi", options->dpi, "PNG resolution, pixels per inch")->capture_default_str();
  cmd->add_flag("--no-label", *no_label, "do not print ids, sizes and the sheet's name");
  cmd->footer(
      "Example: rig target --target config/targets/paper.toml --out paper.pdf\n"
      "Print at 100 % (actual size), never 'fit to page', and check a marker side with a ruler.");
  cmd->callback([&status, layout, out, options, no_label] {
    options->label = !*no_label;
    const vision::Codebook codebook;
    vision::Target target;
    try {
      vision::artwork_format_from_path(*out);
      target = vision::Target::load(*layout);
      for (const vision::TargetMarker& m : target.markers) {
        if (static_cast<size_t>(m.id) >= codebook.size()) {
          throw vision::TargetError(*layout + ": marker id " + std::to_string(m.id) +
                                    ": expected a codebook id 0 .. " +
                                    std::to_string(codebook.size() - 1));
        }
      }
    } catch (const std::runtime_error& e) {  // ArtworkError or TargetError: the input
      std::cerr << "rig target: " << e.what() << "\n";
      status.code = kExitBadInput;
      return;
    }
    try {
      vision::write_target_artwork(codebook, target, *options, *out);
    } catch (const std::runtime_error& e) {
      std::cerr << "rig target: " << e.what() << "\n";
      status.code = kExitFailure;
      return;
    }
    std::cout << "wrote " << target.markers.size() << " markers on a "
              << target.sheet_width_m * 1000 << " x " << target.sheet_height_m * 1000
              << " mm sheet to " << *out << "\n";
    status.code = kExitOk;
  });
}

}  // namespace rig::cli
