// rig marker: one coded marker at true physical size, to print.
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "vision/artwork.hpp"
#include "vision/marker_family.hpp"

namespace rig::cli {
namespace {

// The input, checked before anything is written. An unknown extension is a
// vision::ArtworkError, as is a file that cannot be written; write_marker
// runs this through read_input to tell them apart (exit 2, not 1).
const vision::MarkerFamily& check_marker(const std::string& family_name, int id,
                                         const vision::MarkerArtworkOptions& options,
                                         const std::string& out) {
  vision::artwork_format_from_path(out);
  const vision::MarkerFamily* family = nullptr;
  try {
    family = &vision::MarkerFamily::named(family_name);
  } catch (const vision::MarkerFamilyError&) {
    throw BadInput("--family \"" + family_name + "\": expected one of " +
                   vision::MarkerFamily::names_text());
  }
  if (!family->has_id(id))
    throw BadInput("--id " + std::to_string(id) + ": expected 0 .. " +
                   std::to_string(family->size() - 1) + " (the ids of " + family_name + ")");
  if (!(options.side_mm > 0) || options.quiet_cells < 0 ||
      !(options.dpi >= 10 && options.dpi <= 4800))
    throw BadInput("--size-mm must be > 0, --quiet-cells >= 0 and --dpi in 10 .. 4800 (got " +
                   std::to_string(options.side_mm) + ", " + std::to_string(options.quiet_cells) +
                   ", " + std::to_string(options.dpi) + ")");
  return *family;
}

int write_marker(const std::string& family_name, int id,
                 const vision::MarkerArtworkOptions& options, const std::string& out) {
  const vision::MarkerFamily* family = nullptr;
  read_input("", [&] { family = &check_marker(family_name, id, options, out); });
  vision::write_marker_artwork(*family, id, options, out);
  const int n = family->marker_cells();
  const double page_mm = options.side_mm * (n + 2 * options.quiet_cells) / n;
  std::cout << "wrote " << family_name << " marker id " << id << ", " << options.side_mm
            << " mm, page " << page_mm << " x " << page_mm << " mm, to " << out << "\n";
  return kExitOk;
}

}  // namespace

void add_marker_command(CLI::App& app, ExitStatus& status) {
  auto* cmd = app.add_subcommand(
      "marker", "Write one coded marker at true physical size as SVG, PDF or PNG (by extension)");
  auto args = std::make_shared<vision::MarkerArtworkOptions>();
  auto id = std::make_shared<int>(0);
  auto out = std::make_shared<std::string>();
  auto no_label = std::make_shared<bool>(false);
  auto family = std::make_shared<std::string>(vision::MarkerFamily::kDefaultName);
  cmd->add_option("--id", *id, "id in the family (0 .. 34 for rig4x4)")->required();
  cmd->add_option("--family", *family, "marker family: " + vision::MarkerFamily::names_text())
      ->capture_default_str();
  cmd->add_option("--size-mm", args->side_mm,
                  "outer side of the black border, mm (6 x 6 cells for rig4x4)")
      ->capture_default_str();
  cmd->add_option("--out", *out, "output file: .svg, .pdf or .png")->required();
  cmd->add_option("--dpi", args->dpi, "PNG resolution, pixels per inch")->capture_default_str();
  cmd->add_option("--quiet-cells", args->quiet_cells,
                  "white margin around the border, in cells of the marker")
      ->capture_default_str();
  cmd->add_flag("--no-label", *no_label, "do not print the id and size in the margin");
  cmd->footer(
      "Example: rig marker --id 0 --size-mm 50 --out marker0.pdf\n"
      "Print at 100 % (actual size), never 'fit to page', and check the side with a ruler.");
  cmd->callback([&status, args, id, out, no_label, family] {
    args->label = !*no_label;
    status.code = run_command("marker", [&] { return write_marker(*family, *id, *args, *out); });
  });
}

}  // namespace rig::cli
