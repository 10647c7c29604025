// config::Document and config::Table: every getter's accepted and refused
// values, unknown keys, codes in hex and decimal, syntax errors, and files
// that are folders, devices or too big, each refused with the one message form
// "FILE: TABLE.KEY = VALUE: [PROBLEM; ]expected WHAT" and the caller's error type.
#include "config/reader.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;

// The error type of a module that reads a configuration file.
class ExampleError : public config::ConfigError {
 public:
  using config::ConfigError::ConfigError;
};

config::Document parse(const std::string& text) {
  return config::Document::parse<ExampleError>(text, "dir/f.toml", "the example file");
}

// The message of the ExampleError that `read` throws, or "(accepted)".
template <typename Read>
std::string error_of(Read read) {
  try {
    read();
  } catch (const ExampleError& e) {
    return e.what();
  }
  return "(accepted)";
}

// A fresh folder for one test's files.
fs::path temp_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("config_reader_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string write_file(const fs::path& path, const std::string& content) {
  std::ofstream(path, std::ios::binary) << content;
  return path.string();
}

// ---- files --------------------------------------------------------------

TEST(ReadTextFile, GivesTheBytesOfARegularFile) {
  const fs::path dir = temp_dir("bytes");
  const std::string text = std::string("a = 1\n\0b\r\n", 10);
  EXPECT_EQ(config::read_text_file(write_file(dir / "f.toml", text), "the example file",
                                   &config::raise_as<ExampleError>),
            text);
}

TEST(ReadTextFile, RefusesAMissingFileNamingPathAndRole) {
  EXPECT_EQ(error_of([] {
              config::read_text_file("/nonexistent/f.toml", "the example file",
                                     &config::raise_as<ExampleError>);
            }),
            "/nonexistent/f.toml: does not exist; expected the example file");
}

TEST(ReadTextFile, RefusesAFolder) {
  const fs::path dir = temp_dir("folder");
  EXPECT_EQ(
      error_of([&] { config::Document::read<ExampleError>(dir.string(), "the example file"); }),
      dir.string() + ": is a folder; expected the example file, a regular file");
}

TEST(ReadTextFile, RefusesAFifo) {
  const fs::path dir = temp_dir("fifo");
  const std::string path = (dir / "pipe").string();
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  // Refused before it is opened: opening a FIFO without a writer would block.
  EXPECT_EQ(error_of([&] { config::Document::read<ExampleError>(path, "the example file"); }),
            path +
                ": is not a regular file (a device, FIFO or socket); expected the example "
                "file, a regular file");
}

TEST(ReadTextFile, RefusesAFileOverTheBoundAndAcceptsOneAtIt) {
  const fs::path dir = temp_dir("size");
  const std::string at_bound = write_file(dir / "at.toml", std::string(config::kMaxFileBytes, '#'));
  EXPECT_EQ(
      config::read_text_file(at_bound, "the example file", &config::raise_as<ExampleError>).size(),
      config::kMaxFileBytes);
  const std::string over =
      write_file(dir / "over.toml", std::string(config::kMaxFileBytes + 1, '#'));
  EXPECT_EQ(error_of([&] { config::Document::read<ExampleError>(over, "the example file"); }),
            over +
                ": 1048577 bytes, more than any hand-written file; expected the example file, "
                "a regular file of at most 1048576 bytes");
}

TEST(Document, ReadKeepsPathAndTextAndParses) {
  const fs::path dir = temp_dir("read");
  const std::string path = write_file(dir / "f.toml", "n = 7\n");
  const config::Document doc = config::Document::read<ExampleError>(path, "the example file");
  EXPECT_EQ(doc.source(), path);
  EXPECT_EQ(doc.text(), "n = 7\n");
  EXPECT_EQ(doc.root().integer("n", 0, 10), 7);
}

TEST(Document, SyntaxErrorNamesFileLineAndColumn) {
  // The description between is toml++'s own.
  const std::string message = error_of([] { parse("a = 1\nb = = 2\n"); });
  const std::string where = "dir/f.toml: line 2, column 5: ";
  EXPECT_EQ(message.substr(0, where.size()), where) << message;
  EXPECT_GT(message.size(), where.size() + 21) << message;
  EXPECT_EQ(message.substr(message.size() - 21), "; expected valid TOML") << message;
}

TEST(Document, EveryErrorIsTheCallersTypeAndAConfigError) {
  EXPECT_THROW(parse("x = ["), ExampleError);
  EXPECT_THROW(parse("x = ["), config::ConfigError);
  config::Table root = parse("x = 1").root();
  EXPECT_THROW(root.string("x", "a string"), ExampleError);
}

TEST(Document, ARaiseThatReturnsStillThrowsAConfigError) {
  const config::Raise returns = [](const std::string&) {};
  EXPECT_THROW(config::Document::parse("x = [", "f.toml", "the example file", returns),
               config::ConfigError);
}

// ---- getters ------------------------------------------------------------

TEST(Integer, AcceptsAnIntegerInRangeOnly) {
  config::Table t = parse("n = 5\nlow = -1\nf = 5.0\ns = \"5\"\nhex = 0x10").root();
  EXPECT_EQ(t.integer("n", 0, 5), 5);
  EXPECT_EQ(t.integer("hex", 0, 100), 16);
  EXPECT_EQ(error_of([&] { t.integer("low", 0, 5); }),
            "dir/f.toml: low = -1: expected an integer in 0..5");
  EXPECT_EQ(error_of([&] { t.integer("f", 0, 10); }),
            "dir/f.toml: f = 5.0: expected an integer in 0..10");
  EXPECT_EQ(error_of([&] { t.integer("s", 0, 10); }),
            "dir/f.toml: s = \"5\": expected an integer in 0..10");
  EXPECT_EQ(error_of([&] { t.integer("none", 0, 10, "a count >= 0"); }),
            "dir/f.toml: none: missing; expected a count >= 0");
}

TEST(Integer, OptionalGivesTheDefaultOnlyWhenAbsent) {
  config::Table t = parse("n = 11").root();
  EXPECT_EQ(t.integer_or("absent", 3, 0, 10), 3);
  EXPECT_EQ(error_of([&] { t.integer_or("n", 3, 0, 10); }),
            "dir/f.toml: n = 11: expected an integer in 0..10");
}

TEST(Number, AcceptsFiniteIntegersAndFloatsThatTheRuleAccepts) {
  config::Table t =
      parse("i = 2\nf = 2.5\nneg = -1.0\nbig = inf\nnan = nan\ns = \"2\"\nb = true").root();
  EXPECT_EQ(t.number("i"), 2.0);
  EXPECT_EQ(t.number("f", config::positive()), 2.5);
  EXPECT_EQ(error_of([&] { t.number("neg", config::positive()); }),
            "dir/f.toml: neg = -1.0: expected a number > 0");
  EXPECT_EQ(error_of([&] { t.number("neg", config::non_negative()); }),
            "dir/f.toml: neg = -1.0: expected a number >= 0");
  EXPECT_EQ(error_of([&] { t.number("big"); }), "dir/f.toml: big = inf: expected a finite number");
  EXPECT_EQ(error_of([&] { t.number("nan"); }), "dir/f.toml: nan = nan: expected a finite number");
  EXPECT_EQ(error_of([&] { t.number("s"); }), "dir/f.toml: s = \"2\": expected a finite number");
  EXPECT_EQ(error_of([&] { t.number("b"); }), "dir/f.toml: b = true: expected a finite number");
  const config::NumberRule speed{"a speed in (0, 2] mm/s",
                                 [](double v) { return v > 0 && v <= 2; }};
  EXPECT_EQ(error_of([&] { t.number("f", speed); }),
            "dir/f.toml: f = 2.5: expected a speed in (0, 2] mm/s");
  EXPECT_EQ(error_of([&] { t.number("absent", speed); }),
            "dir/f.toml: absent: missing; expected a speed in (0, 2] mm/s");
}

TEST(Number, OptionalGivesTheDefaultOrNothingWhenAbsent) {
  config::Table t = parse("f = -2.5").root();
  EXPECT_EQ(t.number_or("absent", 4.0), 4.0);
  EXPECT_FALSE(t.optional_number("absent").has_value());
  EXPECT_EQ(t.optional_number("f"), -2.5);
  EXPECT_EQ(error_of([&] { t.number_or("f", 1.0, config::positive()); }),
            "dir/f.toml: f = -2.5: expected a number > 0");
  EXPECT_EQ(error_of([&] { t.optional_number("f", config::positive()); }),
            "dir/f.toml: f = -2.5: expected a number > 0");
}

TEST(Boolean, AcceptsTrueAndFalseOnly) {
  config::Table t = parse("yes = true\nno = false\none = 1\ns = \"true\"").root();
  EXPECT_TRUE(t.boolean("yes"));
  EXPECT_FALSE(t.boolean_or("no", true));
  EXPECT_TRUE(t.boolean_or("absent", true));
  EXPECT_EQ(error_of([&] { t.boolean("one"); }), "dir/f.toml: one = 1: expected true or false");
  EXPECT_EQ(error_of([&] { t.boolean_or("s", false); }),
            "dir/f.toml: s = \"true\": expected true or false");
  EXPECT_EQ(error_of([&] { t.boolean("absent"); }),
            "dir/f.toml: absent: missing; expected true or false");
}

TEST(String, AcceptsStringsOnly) {
  config::Table t = parse("s = \"text\"\nn = 5\nquote = 'say \"hi\"'").root();
  EXPECT_EQ(t.string("s", "a name"), "text");
  EXPECT_EQ(t.string_or("absent", "dflt", "a name"), "dflt");
  EXPECT_EQ(error_of([&] { t.string("n", "a name"); }), "dir/f.toml: n = 5: expected a name");
  EXPECT_EQ(error_of([&] { t.string_or("n", "x", "a name"); }),
            "dir/f.toml: n = 5: expected a name");
  // The value as written, quotes escaped.
  EXPECT_EQ(error_of([&] { t.integer("quote", 0, 1); }),
            "dir/f.toml: quote = \"say \\\"hi\\\"\": expected an integer in 0..1");
}

TEST(Choice, AcceptsOneOfTheOptions) {
  config::Table t = parse("kind = \"grid\"\nbad = \"spiral\"\nn = 1").root();
  EXPECT_EQ(t.choice("kind", {"grid", "csv", "paper"}), "grid");
  EXPECT_EQ(t.choice_or("absent", "csv", {"grid", "csv"}), "csv");
  EXPECT_EQ(error_of([&] {
              t.choice("bad", {"grid", "csv", "paper"});
            }),
            "dir/f.toml: bad = \"spiral\": expected \"grid\", \"csv\" or \"paper\"");
  EXPECT_EQ(error_of([&] {
              t.choice_or("n", "a", {"a", "b"});
            }),
            "dir/f.toml: n = 1: expected \"a\" or \"b\"");
}

TEST(Strings, AcceptsAnArrayOfStringsOfTheGivenSizes) {
  config::Table t =
      parse("argv = [\"python3\", \"x y.py\"]\nnone = []\nmixed = [\"a\", 1]\ns = \"a\"").root();
  EXPECT_EQ(t.strings("argv", 1, 4, "a command"), (std::vector<std::string>{"python3", "x y.py"}));
  EXPECT_EQ(error_of([&] { t.strings("none", 1, 4, "a command"); }),
            "dir/f.toml: none = []: expected a command");
  EXPECT_EQ(error_of([&] { t.strings("argv", 1, 1, "one program"); }),
            "dir/f.toml: argv = [\"python3\", \"x y.py\"]: expected one program");
  EXPECT_EQ(error_of([&] { t.strings("mixed", 1, 4, "a command"); }),
            "dir/f.toml: mixed = [\"a\", 1]: expected a command");
  EXPECT_EQ(error_of([&] { t.strings("s", 1, 4, "a command"); }),
            "dir/f.toml: s = \"a\": expected a command");
  EXPECT_EQ(error_of([&] { t.strings("absent", 1, 4, "a command"); }),
            "dir/f.toml: absent: missing; expected a command");
}

TEST(Numbers, AcceptsAnArrayOfFiniteNumbersOfTheGivenSizes) {
  config::Table t =
      parse("v = [1, 2.5, -3]\nshort = [1]\nmixed = [1, \"2\", 3]\ninf = [1, inf, 3]\nn = 3")
          .root();
  EXPECT_EQ(t.numbers("v", 3, 3, "[x, y, z]"), (std::vector<double>{1, 2.5, -3}));
  EXPECT_EQ(t.numbers("v", 2, 3, "[a, b] or [a, b, c]").size(), 3u);
  EXPECT_EQ(error_of([&] { t.numbers("short", 2, 3, "[x, y]"); }),
            "dir/f.toml: short = [1]: expected [x, y]");
  EXPECT_EQ(error_of([&] { t.numbers("v", 2, 2, "[x, y]"); }),
            "dir/f.toml: v = [1, 2.5, -3]: expected [x, y]");
  EXPECT_EQ(error_of([&] { t.numbers("mixed", 3, 3, "[x, y, z]"); }),
            "dir/f.toml: mixed = [1, \"2\", 3]: expected [x, y, z]");
  EXPECT_EQ(error_of([&] { t.numbers("inf", 3, 3, "[x, y, z]"); }),
            "dir/f.toml: inf = [1, inf, 3]: expected [x, y, z]");
  EXPECT_EQ(error_of([&] { t.numbers("n", 3, 3, "[x, y, z]"); }),
            "dir/f.toml: n = 3: expected [x, y, z]");
}

TEST(Paths, AreResolvedAgainstTheFilesFolderAndMustNameAFile) {
  const fs::path dir = temp_dir("paths");
  fs::create_directories(dir / "sub");
  write_file(dir / "sub" / "plan.csv", "x_mm,y_mm\n");
  const std::string file = write_file(dir / "f.toml",
                                      "plan = \"sub/../sub/plan.csv\"\nnone = \"none.csv\"\n"
                                      "folder = \"sub\"\nempty = \"\"\nabs = \"/etc/hostname\"\n");
  config::Table t = config::Document::read<ExampleError>(file, "the example file").root();
  EXPECT_EQ(t.existing_file("plan", "a CSV plan"), (dir / "sub" / "plan.csv").string());
  EXPECT_EQ(t.resolve("/abs/x"), "/abs/x");
  EXPECT_EQ(t.resolve("a/./b"), (dir / "a" / "b").string());
  EXPECT_EQ(error_of([&] { t.existing_file("none", "a CSV plan"); }),
            file + ": none = \"none.csv\": " + (dir / "none.csv").string() +
                " is not an existing file; expected the path of a CSV plan (relative to the "
                "example file)");
  EXPECT_EQ(error_of([&] { t.existing_file("folder", "a CSV plan"); }),
            file + ": folder = \"sub\": " + (dir / "sub").string() +
                " is not an existing file; expected the path of a CSV plan (relative to the "
                "example file)");
  EXPECT_EQ(error_of([&] { t.existing_file("empty", "a CSV plan"); }),
            file + ": empty = \"\": expected the path of a CSV plan");
  EXPECT_EQ(error_of([&] { t.existing_file("absent", "a CSV plan"); }),
            file + ": absent: missing; expected the path of a CSV plan");
}

// ---- tables -------------------------------------------------------------

TEST(Tables, RequiredOptionalAndArraysOfTablesAreNamedByTheirDottedPath) {
  config::Table root = parse(
                           "flat = 3\n[sim]\n[sim.x]\naccel = -1\n[[markers]]\nid = 0\n"
                           "[[markers]]\nid = \"one\"\n")
                           .root();
  config::Table x = root.table("sim").table("x");
  EXPECT_EQ(x.name(), "sim.x");
  EXPECT_EQ(error_of([&] { x.number("accel", config::positive()); }),
            "dir/f.toml: sim.x.accel = -1: expected a number > 0");
  const std::vector<config::Table> markers = root.tables("markers", "[[markers]] tables");
  ASSERT_EQ(markers.size(), 2u);
  config::Table second = markers[1];
  EXPECT_EQ(error_of([&] { second.integer("id", 0, 9); }),
            "dir/f.toml: markers[1].id = \"one\": expected an integer in 0..9");
  EXPECT_EQ(error_of([&] { root.table("absent"); }),
            "dir/f.toml: absent: missing; expected a table [absent]");
  EXPECT_EQ(error_of([&] { root.table("flat"); }), "dir/f.toml: flat = 3: expected a table [flat]");
  EXPECT_EQ(error_of([&] { root.optional_table("flat"); }),
            "dir/f.toml: flat = 3: expected a table [flat]");
  EXPECT_EQ(error_of([&] { root.tables("flat", "[[flat]] tables"); }),
            "dir/f.toml: flat = 3: expected [[flat]] tables");
}

TEST(Tables, AnAbsentOptionalTableGivesDefaultsAndReportsRequiredKeysMissing) {
  config::Table root = parse("a = 1").root();
  config::Table settle = root.optional_table("settle");
  EXPECT_FALSE(settle.exists());
  EXPECT_EQ(settle.integer_or("dwell_ms", 7, 0, 10), 7);
  EXPECT_FALSE(settle.has("dwell_ms"));
  EXPECT_NO_THROW(settle.reject_unknown());
  EXPECT_EQ(error_of([&] { settle.integer("timeout_ms", 1, 10); }),
            "dir/f.toml: settle.timeout_ms: missing; expected an integer in 1..10");
}

TEST(Tables, AnEmptyArrayOrAnArrayOfNonTablesIsRefused) {
  config::Table root = parse("markers = []\nids = [1, 2]").root();
  EXPECT_EQ(error_of([&] { root.tables("markers", "[[markers]] tables"); }),
            "dir/f.toml: markers = []: expected [[markers]] tables");
  EXPECT_EQ(error_of([&] { root.tables("ids", "[[ids]] tables"); }),
            "dir/f.toml: ids = [1, 2]: expected [[ids]] tables");
}

TEST(Tables, ToTomlGivesADocumentWithTheSameKeys) {
  config::Table rig =
      parse("[rig.camera_mount]\noffset_mm = [0.0, 1.5, 0.0]\n[rig.target]\nname = \"x\"\n")
          .root()
          .table("rig");
  config::Table back = parse(rig.to_toml()).root();
  EXPECT_EQ(back.table("camera_mount").numbers("offset_mm", 3, 3, "[x, y, z]"),
            (std::vector<double>{0, 1.5, 0}));
  config::Table target = back.table("target");
  EXPECT_EQ(target.string("name", "a name"), "x");
  target.reject_unknown();
  back.reject_unknown();
  EXPECT_EQ(parse("").root().optional_table("absent").to_toml(), "");
}

// ---- unknown keys -------------------------------------------------------

TEST(RejectUnknown, RefusesAKeyNoGetterAskedForListingTheAskedKeysInOrder) {
  config::Table t = parse("[motion]\nspeed = 1\nsettle_tme_ms = 5\n").root().table("motion");
  t.number("speed");
  t.integer_or("settle_time_ms", 0, 0, 10);  // absent, still one of the keys
  EXPECT_EQ(error_of([&] { t.reject_unknown(); }),
            "dir/f.toml: motion.settle_tme_ms = 5: unknown key (misspelt?); expected one of "
            "speed, settle_time_ms");
  EXPECT_EQ(error_of([&] { t.reject_unknown("one of the documented keys"); }),
            "dir/f.toml: motion.settle_tme_ms = 5: unknown key (misspelt?); expected one of the "
            "documented keys");
}

TEST(RejectUnknown, AcceptsIgnoredKeysAndTablesTakenAsTables) {
  config::Table root = parse("name = \"n\"\n[sim]\nx = 1\n[link]\nid = 1\n").root();
  root.string("name", "a name");
  root.ignore("sim");
  config::Table link = root.table("link");
  EXPECT_NO_THROW(root.reject_unknown());
  EXPECT_EQ(error_of([&] { link.reject_unknown(); }),
            "dir/f.toml: link.id = 1: unknown key (misspelt?); expected no key in link");
}

TEST(RejectUnknown, NamesAnUnknownTableWithItsContentInline) {
  config::Table root = parse("[setle]\ndwell_ms = 0\nlist = [1, \"a\"]\n").root();
  root.optional_table("settle");
  EXPECT_EQ(error_of([&] { root.reject_unknown(); }),
            "dir/f.toml: setle = { dwell_ms = 0, list = [1, \"a\"] }: unknown key (misspelt?); "
            "expected one of settle");
}

// ---- tables keyed by codes ----------------------------------------------

TEST(StringsByCode, AcceptsDecimalAndHexKeysAsTheSameCodes) {
  config::Table alarms =
      parse("[alarms]\n0xB1 = \"overload\"\n2 = \"following error\"\n0x0a = \"ten\"\n")
          .root()
          .table("alarms");
  const std::map<std::int64_t, std::string> codes =
      alarms.strings_by_code(1, 65535, "an alarm code", "the alarm's meaning, a string");
  EXPECT_EQ(codes, (std::map<std::int64_t, std::string>{
                       {2, "following error"}, {10, "ten"}, {177, "overload"}}));
  EXPECT_NO_THROW(alarms.reject_unknown());
  EXPECT_EQ(parse("[alarms]\n177 = \"overload\"\n")
                .root()
                .table("alarms")
                .strings_by_code(1, 65535, "an alarm code", "a string"),
            (std::map<std::int64_t, std::string>{{177, "overload"}}));
}

TEST(StringsByCode, RefusesACodeWrittenTwiceNamingBothSpellings) {
  config::Table alarms =
      parse("[alarms]\n177 = \"overload\"\n0xB1 = \"overload\"\n").root().table("alarms");
  EXPECT_EQ(error_of([&] { alarms.strings_by_code(1, 65535, "an alarm code", "a string"); }),
            "dir/f.toml: alarms.177 = \"overload\": code 177 is also written as alarms.0xB1; "
            "expected each code once");
}

TEST(StringsByCode, RefusesKeysThatAreNotCodesInRangeAndValuesThatAreNotStrings) {
  const std::string expected =
      "expected an alarm code in 1..65535 as the key, in decimal (177) or hex (0xB1)";
  for (const char* key : {"overload", "0", "65536", "0x10000", "0177", "0x", "-1", "1.5", "0xG1"}) {
    config::Table alarms =
        parse("[alarms]\n\"" + std::string(key) + "\" = \"x\"\n").root().table("alarms");
    EXPECT_EQ(error_of([&] { alarms.strings_by_code(1, 65535, "an alarm code", "a string"); }),
              "dir/f.toml: alarms." + std::string(key) + " = \"x\": " + expected)
        << key;
  }
  config::Table alarms = parse("[alarms]\n3 = 4\n").root().table("alarms");
  EXPECT_EQ(error_of([&] { alarms.strings_by_code(1, 65535, "an alarm code", "a string"); }),
            "dir/f.toml: alarms.3 = 4: expected a string");
}

// ---- messages -----------------------------------------------------------

TEST(Messages, FailNamesTheValueAsWrittenOrSaysItIsMissing) {
  config::Table t =
      parse("long = \"" + std::string(120, 'a') + "\"\nt = { a = 1, b = [2, 3] }\n").root();
  EXPECT_EQ(error_of([&] { t.fail("t", "a valid t", "b is too long"); }),
            "dir/f.toml: t = { a = 1, b = [2, 3] }: b is too long; expected a valid t");
  EXPECT_EQ(error_of([&] { t.fail("absent", "a timeout", "not given, so 25000 ms applies"); }),
            "dir/f.toml: absent: not given, so 25000 ms applies; expected a timeout");
  const std::string cut = error_of([&] { t.fail("long", "short"); });
  EXPECT_EQ(cut, "dir/f.toml: long = \"" + std::string(96, 'a') + "...: expected short");
}

TEST(Messages, ErrorMessageAndNumbersHaveTheCommonForm) {
  EXPECT_EQ(config::error_message("p.toml", "registers.target_y", std::string("1"),
                                  "registers of its own", "registers 1..2 overlap target_x"),
            "p.toml: registers.target_y = 1: registers 1..2 overlap target_x; expected registers "
            "of its own");
  EXPECT_EQ(config::error_message("p.toml", "name", std::nullopt, "a string"),
            "p.toml: name: missing; expected a string");
  EXPECT_EQ(config::format_number(0.1 + 0.2), "0.3");
  EXPECT_EQ(config::format_number(1500), "1500");
  EXPECT_EQ(config::format_number(-0.0001), "-0.0001");
}

}  // namespace
