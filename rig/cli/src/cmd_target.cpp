// rig target: a whole target sheet (A4 or A3) from a layout file, to print.
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "vision/artwork.hpp"
#include "vision/target.hpp"

namespace rig::cli {
namespace {

int write_target(const std::string& layout, const vision::TargetArtworkOptions& options,
                 const std::string& out) {
  vision::Target target;
  // Bad input (exit 2) first: an unknown extension is an ArtworkError, as is
  // a file that cannot be written (exit 1).
  read_input("", [&] {
    vision::artwork_format_from_path(out);
    // Checks the family and that every id is one of its ids.
    target = vision::Target::load(layout);
  });
  vision::write_target_artwork(target, options, out);
  std::cout << "wrote " << target.markers.size() << " " << target.family << " markers on a "
            << target.sheet_width_m * 1000 << " x " << target.sheet_height_m * 1000
            << " mm sheet to " << out << "\n";
  return kExitOk;
}

}  // namespace

void add_target_command(CLI::App& app, ExitStatus& status) {
  auto* cmd = app.add_subcommand(
      "target", "Write a target sheet at true physical size as SVG, PDF or PNG (by extension)");
  auto layout = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto options = std::make_shared<vision::TargetArtworkOptions>();
  auto no_label = std::make_shared<bool>(false);
  cmd->add_option(
         "--target", *layout,
         "layout file (TOML: paper, origin_mm, pose_marker, family, [[markers]] id, side_mm, "
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
    status.code = run_command("target", [&] { return write_target(*layout, *options, *out); });
  });
}

}  // namespace rig::cli
