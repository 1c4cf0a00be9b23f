// Every shipped configuration file parses; bad files are refused with file, line and reason.
#include "slam_configuration.h"

#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"

#include <algorithm>
#include <filesystem>
#include <sstream>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/io/input_error.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

template <typename Action>
std::string ErrorOf(Action action) {
  try {
    action();
  } catch (const std::exception& error) {
    return error.what();
  }
  return "";
}

TEST(Configuration, EveryShippedConfigFileParses) {
  // Each YAML in config/ with the reader it is meant for: calibration, place recognition, or
  // odometry (euroc.yaml and its presets).
  int odometry = 0, others = 0;
  const features::FeatureOptions defaults;
  for (const auto& entry : std::filesystem::directory_iterator(RepositoryRoot() + "/config")) {
    const std::string path = entry.path().string();
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() != ".yaml") continue;
    if (name == "euroc_stereo.yaml") {
      EXPECT_NO_THROW(camera::ReadStereoCalibrationYaml(path)) << path;
      ++others;
    } else if (name == "fabmap.yaml") {
      EXPECT_NO_THROW(place_recognition::LoadPlaceRecognitionOptions(path, defaults)) << path;
      ++others;
    } else {
      EXPECT_NO_THROW(tools::SlamConfiguration::Load(path)) << path;
      ++odometry;
    }
  }
  EXPECT_EQ(odometry, 4);  // euroc.yaml and the three keyframe presets
  EXPECT_EQ(others, 2);
}

TEST(Configuration, DefaultsEqualTheShippedEurocFile) {
  // config/euroc.yaml documents the defaults: printing both must give the same text.
  std::ostringstream from_file, defaults;
  tools::SlamConfiguration::Load(RepositoryRoot() + "/config/euroc.yaml").Print(from_file);
  tools::SlamConfiguration{}.Print(defaults);
  EXPECT_EQ(from_file.str(), defaults.str());
}

TEST(Configuration, PresetsOverrideOnlyTheirSection) {
  const tools::SlamConfiguration base =
      tools::SlamConfiguration::Load(RepositoryRoot() + "/config/euroc.yaml");
  const tools::SlamConfiguration less =
      tools::SlamConfiguration::Load(RepositoryRoot() + "/config/keyframes_less.yaml");
  const tools::SlamConfiguration most =
      tools::SlamConfiguration::Load(RepositoryRoot() + "/config/keyframes_most.yaml");
  EXPECT_GT(less.front_end.keyframes.max_translation, base.front_end.keyframes.max_translation);
  EXPECT_LT(most.front_end.keyframes.max_translation, base.front_end.keyframes.max_translation);
  EXPECT_EQ(less.front_end.features.max_features, base.front_end.features.max_features);
  EXPECT_EQ(most.front_end.tracker.pnp_kernel, base.front_end.tracker.pnp_kernel);
}

TEST(Configuration, BadFilesNameTheProblem) {
  TemporaryDirectory temp;
  const std::string path = temp.path() + "/bad.yaml";
  WriteTextFile(path, "features:\n  detector: AGAST\n  max_featurs: 500\n");
  std::string error = ErrorOf([&] { tools::SlamConfiguration::Load(path); });
  EXPECT_NE(error.find("unknown key(s) in 'features': max_featurs"), std::string::npos) << error;
  EXPECT_NE(error.find(path + ":"), std::string::npos) << error;

  WriteTextFile(path, "tracker:\n  ransac_threshold: fast\n");
  error = ErrorOf([&] { tools::SlamConfiguration::Load(path); });
  EXPECT_NE(error.find(path + ":2: tracker.ransac_threshold must be a number"), std::string::npos)
      << error;

  WriteTextFile(path, "trackr:\n  ransac_threshold: 2\n");
  error = ErrorOf([&] { tools::SlamConfiguration::Load(path); });
  EXPECT_NE(error.find("unknown section 'trackr'"), std::string::npos) << error;

  WriteTextFile(path, "tracker:\n  pnp_kernel: DLT\n");
  error = ErrorOf([&] { tools::SlamConfiguration::Load(path); });
  EXPECT_NE(error.find("ITERATIVE, EPNP, AP3P, P3P, SQPNP, UMEYAMA"), std::string::npos) << error;

  WriteTextFile(path, "backend:\n  window: 1\n");
  error = ErrorOf([&] { tools::SlamConfiguration::Load(path); });
  EXPECT_NE(error.find("backend.window"), std::string::npos) << error;

  WriteTextFile(path, "# a preset\ninclude: missing.yaml\n");
  error = ErrorOf([&] { tools::SlamConfiguration::Load(path); });
  EXPECT_NE(error.find("missing.yaml: cannot open file"), std::string::npos) << error;
  EXPECT_NE(error.find("included from " + path + ":2"), std::string::npos) << error;
}

// A bad calibration value is reported at its own line, not at its section's first line.
TEST(Configuration, BadCalibrationValuesNameTheirLine) {
  const std::string original = ReadTextFile(RepositoryRoot() + "/config/euroc_stereo.yaml");
  TemporaryDirectory temp;
  const std::string path = temp.path() + "/calibration.yaml";
  const auto line_of = [&](const std::string& text, const std::string& needle, std::size_t from) {
    const std::size_t at = text.find(needle, from);
    return 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
  };
  const std::size_t right = original.find("right:");
  struct Case {
    std::string from, to, reason;
    std::size_t search_from;
  };
  for (const Case& c :
       {Case{"intrinsics: [458.654", "intrinsics: [-458.654", "focal lengths must be positive", 0},
        Case{"distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, "
             "1.76187114e-05]",
             "distortion_coefficients: [-0.28340811, 0.07395907]", "4 or 5 coefficients", 0},
        Case{"resolution: [752, 480]", "resolution: [640, 480]", "same resolution", right}}) {
    std::string text = original;
    const std::size_t at = text.find(c.from, c.search_from);
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, c.from.size(), c.to);
    WriteTextFile(path, text);
    const std::string error = ErrorOf([&] { camera::ReadStereoCalibrationYaml(path); });
    const std::string where = path + ":" + std::to_string(line_of(text, c.to, c.search_from)) + ":";
    EXPECT_NE(error.find(where), std::string::npos) << where << " not in: " << error;
    EXPECT_NE(error.find(c.reason), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
