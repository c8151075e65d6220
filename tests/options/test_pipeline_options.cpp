// The option model shared by the CLI and Python: one table, one check per option, one message.

#include "options/pipeline_options.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "runtime/error.h"

namespace meshflow::options {
namespace {

// The message validate() gives for `options`, or "" when it accepts them.
std::string problem_of(const PipelineOptions& options) {
  try {
    validate(options);
    return "";
  } catch (const Error& e) {
    return e.what();
  }
}

TEST(PipelineOptions, DefaultsPassEveryCheckAndNamesAreUnique) {
  const PipelineOptions defaults;
  std::set<std::string> names, python_names;
  for (const OptionSpec& spec : pipeline_option_specs()) {
    EXPECT_EQ(spec.check(defaults), "") << spec.name;
    EXPECT_TRUE(names.insert(spec.name).second) << spec.name;
    EXPECT_TRUE(python_names.insert(python_name(spec)).second) << spec.name;
    EXPECT_NE(std::string(spec.help), "") << spec.name;
  }
  EXPECT_EQ(python_names.count("normal_source"), 1u);
  EXPECT_EQ(python_names.count("max_distance"), 1u);
  EXPECT_NO_THROW(defaults.config());
}

// Issue 55: values the CLI refused and Python took (voxel=-5 gave a mesh, max_distance=-1 56
// triangles) are refused by the model, naming the option and the range.
TEST(PipelineOptions, OutOfRangeValuesAreRefusedWithTheOptionAndTheRange) {
  PipelineOptions o;
  o.voxel = -5.0f;
  EXPECT_EQ(problem_of(o), "--voxel: expected a number in [0, 1000], got -5");
  o = {};
  o.voxel = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(problem_of(o).find("--voxel: expected a number in [0, 1000]"), std::string::npos);
  o = {};
  o.kn = -3;
  EXPECT_EQ(problem_of(o), "--kn: expected a number in [3, 1000], got -3");
  o = {};
  o.decimate_to = 5.0f;
  EXPECT_EQ(problem_of(o), "--decimate-to: expected a number in [0, 1], got 5");
  o = {};
  o.max_distance = -1.0f;
  EXPECT_EQ(problem_of(o), "--max-distance: expected a number in (0, 1000], got -1");
  o = {};
  o.depth_median = 4;
  EXPECT_EQ(problem_of(o), "--depth-median: expected one of 0, 3, 5; got 4");
  o = {};
  o.extract = "fast";
  EXPECT_EQ(problem_of(o), "--extract: expected one of auto, mc, mt, emc, pmc; got 'fast'");
  o = {};
  o.max_memory = "lots";
  EXPECT_EQ(problem_of(o),
            "--max-memory: expected a size such as 512M, 4G or 0 (no limit), got 'lots'");
  o = {};
  o.optimize = "clean,foo";
  const std::string optimize = problem_of(o);
  EXPECT_EQ(optimize.find("--optimize: --optimize"), std::string::npos) << optimize;
  EXPECT_NE(optimize.find("'foo'"), std::string::npos) << optimize;
  o = {};
  o.contour_tolerance = -5.0f;  // -1 is the "0.4 voxel" default, other negatives are wrong
  EXPECT_NE(problem_of(o).find("--contour-tolerance"), std::string::npos);
  o.contour_tolerance = -1.0f;
  EXPECT_EQ(problem_of(o), "");
  o.voxel = -5.0f;
  EXPECT_THROW(o.config(), Error);
  o = {};
  o.normal_error = 45.0f;  // 0 (from --normal-bits) or 0.001..30 degrees
  const std::string normal_error = problem_of(o);
  EXPECT_EQ(normal_error.rfind("--normal-error: expected a number in [", 0), 0u) << normal_error;
  EXPECT_NE(normal_error.find("got 45"), std::string::npos) << normal_error;
  o.normal_error = 0.5f;
  EXPECT_EQ(problem_of(o), "");
  EXPECT_DOUBLE_EQ(o.config().compress.normal_error, 0.5);
}

TEST(PipelineOptions, OrientationsParse) {
  NormalsConfig n;
  parse_orientation("up", n);
  EXPECT_EQ(n.orientation, NormalOrientation::kUp);
  parse_orientation("down", n);
  EXPECT_EQ(n.orientation, NormalOrientation::kDown);
  NormalsConfig flip;
  parse_orientation("flip", flip);
  EXPECT_EQ(flip.orientation, NormalOrientation::kAuto);
  EXPECT_TRUE(flip.flip);
  parse_orientation("viewpoint=512000.5,5403000,12", n);
  EXPECT_EQ(n.orientation, NormalOrientation::kTowardViewpoint);
  EXPECT_FLOAT_EQ(n.viewpoint.x(), 512000.5f);
  EXPECT_THROW(parse_orientation("viewpoint=1,2", n), Error);
  EXPECT_THROW(parse_orientation("sideways", n), Error);
}

TEST(PipelineOptions, ByteSizes) {
  EXPECT_EQ(parse_byte_size("512M", "--max-memory"), 512u * 1024 * 1024);
  EXPECT_EQ(parse_byte_size("0", "--max-memory"), 0u);
  EXPECT_THROW(parse_byte_size("-1G", "--max-memory"), Error);
  EXPECT_THROW(parse_byte_size("4X", "--max-memory"), Error);
}

}  // namespace
}  // namespace meshflow::options

namespace meshflow::options {
namespace {

// --crop (issue 55 item 9): six numbers, each min below its max; the box reaches the filter.
TEST(PipelineOptions, CropBoxIsSixNumbersWithMinBelowMax) {
  PipelineOptions o;
  o.crop = "-1,-2,-3,1,2,3.5";
  const ReconstructionConfig c = o.config();
  EXPECT_EQ(c.filter.crop_min, Eigen::Vector3f(-1, -2, -3));
  EXPECT_EQ(c.filter.crop_max, Eigen::Vector3f(1, 2, 3.5f));
  EXPECT_TRUE(PipelineOptions{}.config().filter.keeps_every_finite_point());
  const struct {
    const char* text;
    const char* expected;
  } bad[] = {{"1,2,3", "expected six numbers minx,miny,minz,maxx,maxy,maxz (metres), got '1,2,3'"},
             {"0,0,0,1,1,1,1", "expected six numbers"},
             {"0,0,0,1,1,", "expected six numbers"},
             {"0,0,nan,1,1,1", "expected six numbers"},
             {"0,0,a,1,1,1", "expected six numbers"},
             {"0,0,2,1,1,1", "minz must be below maxz, got 2 and 1 in '0,0,2,1,1,1'"},
             {"1,0,0,1,1,1", "minx must be below maxx"}};
  for (const auto& b : bad) {
    o.crop = b.text;
    EXPECT_NE(problem_of(o).find(std::string("--crop: ") + b.expected), std::string::npos)
        << b.text << ": " << problem_of(o);
  }
}

}  // namespace
}  // namespace meshflow::options
