#pragma once
// How the page shows numbers (private to db_report): each numeric table
// column is converted from SI into the unit a reader of a sweep of 0.1-1 m
// thinks in (mm or µm for lengths, µs for times, % for rates) and written
// with one number of decimals for the whole column, so that digits line up
// and nothing is in e-notation. report.json and the CSV tables keep SI.
#include <string>
#include <vector>

#include "db/report/html_page.hpp"

namespace db::report {

// The SI quantity of a table cell (html::Cell carries the text only; the
// report keeps this beside it).
enum class Quantity {
  kNone,          // not numeric, or a count: written as is
  kLength,        // metres
  kArea,          // square metres (variances of lengths)
  kDuration,      // seconds
  kMicroseconds,  // already in µs (solver times)
  kPixels,        // px
  kPixelsSq,      // px² (variances of image errors)
  kPercent,       // already in %
  kFraction,      // a rate in [0, 1], shown in %
  kPlain,         // dimensionless (slopes, ratios, z, efficiency)
};

// A column's display: multiply the SI value by `scale`, write `decimals`
// places, unit symbol for the header ("" for plain numbers).
struct DisplayUnit {
  double scale = 1;
  int decimals = 0;
  std::string symbol;
};

// The display of a column whose largest finite |value| (SI) is max_abs:
// lengths in mm from 1 mm up, else µm; areas in mm² from 1 mm², else µm²;
// durations in s from 1 s, ms from 1 ms, else µs; fractions in %. Decimals
// give the largest value four significant digits (at most 4 places, none
// from 1000 up; plain numbers one more, so a slope shows 1.0084), so a
// column never rounds its largest entry to 0. NaN or 0
// max_abs: the unit of the smallest range, 2 decimals.
DisplayUnit display_unit(Quantity quantity, double max_abs);

// value * unit.scale with unit.decimals places ("-0.000" written "0.000");
// "n/a" for NaN, "inf"/"-inf" for infinities.
std::string fixed(double value, const DisplayUnit& unit);

// A length in the unit that suits it alone (header lines, captions):
// "2.800 mm", "35.2 µm".
std::string length_text(double metres);

// A numeric cell: the value (SI, as Quantity says) in Cell::value, the
// quantity in Cell::quantity, the text with 6 significant digits (what
// report.json and the CSV tables show).
html::Cell quantity_cell(double value, Quantity quantity, const std::string& css = "num");

// One table ready for the page: in every column, the cells of each quantity
// are rewritten by display_unit of that quantity's largest |value| in the
// column; a header's SI unit "(m)", "(m²)", "(s)" is replaced by the display
// unit when the column holds one quantity (" (%)" appended for fractions).
// Cells with quantity kNone are left as they are.
html::Table display_table(html::Table table);

}  // namespace db::report
