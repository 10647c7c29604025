// rig marker: one coded marker at true physical size, to print.
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "vision/artwork.hpp"
#include "vision/codebook.hpp"

namespace rig::cli {
namespace {

// The input, checked before anything is written. An unknown extension is a
// vision::ArtworkError, as is a file that cannot be written; write_marker
// runs this through read_input to tell them apart (exit 2, not 1).
void check_marker(const vision::Codebook& codebook, int id,
                  const vision::MarkerArtworkOptions& options, const std::string& out) {
  vision::artwork_format_from_path(out);
  if (id < 0 || static_cast<size_t>(id) >= codebook.size())
    throw BadInput("--id " + std::to_string(id) + ": expected 0 .. " +
                   std::to_string(codebook.size() - 1));
  if (!(options.side_mm > 0) || options.quiet_cells < 0 ||
      !(options.dpi >= 10 && options.dpi <= 4800))
    throw BadInput("--size-mm must be > 0, --quiet-cells >= 0 and --dpi in 10 .. 4800 (got " +
                   std::to_string(options.side_mm) + ", " + std::to_string(options.quiet_cells) +
                   ", " + std::to_string(options.dpi) + ")");
}

int write_marker(int id, const vision::MarkerArtworkOptions& options, const std::string& out) {
  const vision::Codebook codebook;
  read_input("", [&] { check_marker(codebook, id, options, out); });
  vision::write_marker_artwork(codebook, id, options, out);
  const double page_mm =
      options.side_mm * (vision::kMarkerCells + 2 * options.quiet_cells) / vision::kMarkerCells;
  std::cout << "wrote marker id " << id << " (code 0x" << std::hex << codebook.code(id) << std::dec
            << "), " << options.side_mm << " mm, page " << page_mm << " x " << page_mm << " mm, to "
            << out << "\n";
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
  cmd->add_option("--id", *id, "codebook id (0 .. 34 with the default codebook)")->required();
  cmd->add_option("--size-mm", args->side_mm,
                  "outer side of the black border, mm (the marker is 6 x 6 cells)")
      ->capture_default_str();
  cmd->add_option("--out", *out, "output file: .svg, .pdf or .png")->required();
  cmd->add_option("--dpi", args->dpi, "PNG resolution, pixels per inch")->capture_default_str();
  cmd->add_option("--quiet-cells", args->quiet_cells,
                  "white margin around the border, in cells (side / 6)")
      ->capture_default_str();
  cmd->add_flag("--no-label", *no_label, "do not print the id and size in the margin");
  cmd->footer(
      "Example: rig marker --id 0 --size-mm 50 --out marker0.pdf\n"
      "Print at 100 % (actual size), never 'fit to page', and check the side with a ruler.");
  cmd->callback([&status, args, id, out, no_label] {
    args->label = !*no_label;
    status.code = run_command("marker", [&] { return write_marker(*id, *args, *out); });
  });
}

}  // namespace rig::cli
