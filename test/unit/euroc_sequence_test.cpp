#include "stereo_fabmap_slam/datasets/euroc_sequence.h"

#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "stereo_fabmap_slam/io/input_error.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

namespace fs = std::filesystem;
using datasets::EurocSequence;
using io::InputError;

// Expects `action` to throw InputError whose message contains every one of `parts`.
template <typename Action>
void ExpectInputError(Action action, std::initializer_list<std::string> parts) {
  try {
    action();
    ADD_FAILURE() << "no error thrown";
  } catch (const InputError& error) {
    const std::string message = error.what();
    for (const std::string& part : parts) {
      EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
    }
  }
}

TEST(EurocSequence, ReadsMh01Subset) {
  const EurocSequence sequence = EurocSequence::Open(EurocSequencePath("MH01_first10s"));
  EXPECT_EQ(sequence.size(), 200u);
  EXPECT_TRUE(sequence.unpaired().empty());
  EXPECT_EQ(sequence.frames().front().timestamp_ns, 1403636584763555584);
  ASSERT_TRUE(sequence.has_ground_truth());
  EXPECT_EQ(sequence.ground_truth().size(), 2790u);  // data.csv has 2,791 lines with its header
  EXPECT_DOUBLE_EQ(sequence.ground_truth().front().pose.translation().x(), 4.689544);

  const camera::StereoCalibration& calibration = sequence.calibration();
  EXPECT_DOUBLE_EQ(calibration.left.fx, 458.654);
  EXPECT_DOUBLE_EQ(calibration.right.cy, 255.238);
  EXPECT_EQ(calibration.left.resolution, cv::Size(752, 480));
  EXPECT_EQ(calibration.left.distortion.size(), 4u);
  EXPECT_NEAR(calibration.left.T_body_camera.translation().y(), -0.064676986768, 1e-12);
  // EuRoC's stereo baseline is about 11 cm.
  EXPECT_NEAR(calibration.T_right_left().translation().norm(), 0.110, 0.002);

  const datasets::StereoImages images = sequence.LoadStereoPair(199);
  EXPECT_EQ(images.left.size(), cv::Size(752, 480));
  EXPECT_EQ(images.right.type(), CV_8UC1);
  EXPECT_EQ(images.timestamp_ns, sequence.frames().back().timestamp_ns);
}

TEST(EurocSequence, ReadsV101WithYamlHeaderAndLateGroundTruth) {
  const EurocSequence sequence = EurocSequence::Open(EurocSequencePath("V101_micro") + "/mav0");
  EXPECT_EQ(sequence.size(), 95u);
  ASSERT_TRUE(sequence.has_ground_truth());
  const double first_truth = sequence.ground_truth().front().timestamp;
  int frames_before_truth = 0;
  for (const datasets::StereoFrameEntry& frame : sequence.frames()) {
    if (frame.timestamp_ns * 1e-9 < first_truth) ++frames_before_truth;
  }
  EXPECT_EQ(frames_before_truth, 21);  // as the data README says
}

// A three-frame ASL folder made from real MH01 files, to be broken in each test.
class BrokenEurocTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string source = EurocSequencePath("MH01_first10s") + "/mav0";
    mav0_ = temp_.path() + "/seq/mav0";
    const EurocSequence original = EurocSequence::Open(source);
    for (const std::string camera : {"cam0", "cam1"}) {
      fs::create_directories(mav0_ + "/" + camera + "/data");
      fs::copy_file(source + "/" + camera + "/sensor.yaml", mav0_ + "/" + camera + "/sensor.yaml");
      std::string list = "#timestamp [ns],filename\n";
      for (int i = 0; i < 3; ++i) {
        const datasets::StereoFrameEntry& frame = original.frames()[i];
        const std::string name = std::to_string(frame.timestamp_ns) + ".png";
        fs::copy_file(camera == "cam0" ? frame.left_path : frame.right_path,
                      mav0_ + "/" + camera + "/data/" + name);
        list += std::to_string(frame.timestamp_ns) + "," + name + "\n";
        stamps_.push_back(frame.timestamp_ns);
      }
      WriteTextFile(mav0_ + "/" + camera + "/data.csv", list);
    }
  }
  std::string ImagePath(const std::string& camera, int i) const {
    return mav0_ + "/" + camera + "/data/" + std::to_string(stamps_[i]) + ".png";
  }
  std::string Root() const { return temp_.path() + "/seq"; }

  TemporaryDirectory temp_;
  std::string mav0_;
  std::vector<std::int64_t> stamps_;
};

TEST_F(BrokenEurocTest, IntactCopyOpens) {
  const EurocSequence sequence = EurocSequence::Open(Root());
  EXPECT_EQ(sequence.size(), 3u);
  EXPECT_FALSE(sequence.has_ground_truth());
  EXPECT_NO_THROW(sequence.LoadStereoPair(2));
}

TEST_F(BrokenEurocTest, MissingFolders) {
  ExpectInputError([&] { EurocSequence::Open(temp_.path() + "/nowhere"); },
                   {"nowhere", "not an EuRoC ASL folder"});
  fs::remove_all(mav0_ + "/cam1/data");
  ExpectInputError([&] { EurocSequence::Open(Root()); }, {"cam1/data", "missing folder"});
}

TEST_F(BrokenEurocTest, MalformedImageListLine) {
  WriteTextFile(mav0_ + "/cam0/data.csv", "#timestamp [ns],filename\n" +
                                              std::to_string(stamps_[0]) + "," +
                                              std::to_string(stamps_[0]) +
                                              ".png\n"
                                              "12x4,foo.png\n");
  ExpectInputError([&] { EurocSequence::Open(Root()); },
                   {"cam0/data.csv:3:", "expected an integer", "12x4"});
  WriteTextFile(mav0_ + "/cam0/data.csv", "#timestamp [ns],filename\n123\n");
  ExpectInputError([&] { EurocSequence::Open(Root()); }, {"cam0/data.csv:2:", "filename"});
}

TEST_F(BrokenEurocTest, ListedImageMissing) {
  fs::remove(ImagePath("cam1", 1));
  ExpectInputError([&] { EurocSequence::Open(Root()); },
                   {"cam1/data.csv:3:", std::to_string(stamps_[1]) + ".png", "does not exist"});
}

TEST_F(BrokenEurocTest, UnreadableAndWrongSizeImages) {
  WriteTextFile(ImagePath("cam0", 1), "this is not a PNG");
  cv::imwrite(ImagePath("cam1", 2), cv::Mat(100, 120, CV_8UC1, cv::Scalar(7)));
  const EurocSequence sequence = EurocSequence::Open(Root());  // images load lazily
  EXPECT_NO_THROW(sequence.LoadStereoPair(0));
  ExpectInputError([&] { sequence.LoadStereoPair(1); },
                   {ImagePath("cam0", 1), "cannot read image"});
  ExpectInputError([&] { sequence.LoadStereoPair(2); },
                   {ImagePath("cam1", 2), "image is 120x100", "752x480"});
}

TEST_F(BrokenEurocTest, UnpairedFramesAreReportedNotFatal) {
  WriteTextFile(mav0_ + "/cam1/data.csv",
                "#timestamp [ns],filename\n" + std::to_string(stamps_[0]) + "," +
                    std::to_string(stamps_[0]) + ".png\n" + std::to_string(stamps_[2]) + "," +
                    std::to_string(stamps_[2]) + ".png\n");
  const EurocSequence sequence = EurocSequence::Open(Root());
  EXPECT_EQ(sequence.size(), 2u);
  ASSERT_EQ(sequence.unpaired().size(), 1u);
  EXPECT_EQ(sequence.unpaired()[0].camera, "cam0");
  EXPECT_EQ(sequence.unpaired()[0].timestamp_ns, stamps_[1]);
}

TEST_F(BrokenEurocTest, GroundTruthWith8OrMoreColumnsAndBadLines) {
  const std::string path = mav0_ + "/state_groundtruth_estimate0/data.csv";
  WriteTextFile(path,
                "#timestamp, p x, p y, p z, q w, q x, q y, q z, v x, v y, v z, bw x, bw y, bw z, "
                "ba x, ba y, ba z\n"
                "1000000000,1,2,3,1,0,0,0,0.1,0.2,0.3,0,0,0,0,0,0\n"
                "1005000000,1.5,2,3,0,1,0,0,0.1,0.2,0.3,0,0,0,0,0,0\n");
  const EurocSequence sequence = EurocSequence::Open(Root());
  ASSERT_EQ(sequence.ground_truth().size(), 2u);
  EXPECT_DOUBLE_EQ(sequence.ground_truth()[1].timestamp, 1.005);
  EXPECT_DOUBLE_EQ(sequence.ground_truth()[1].pose.translation().x(), 1.5);
  EXPECT_NEAR(sequence.ground_truth()[1].pose.linear()(1, 1), -1.0, 1e-12);  // 180 deg about x

  WriteTextFile(path, "#t,x,y,z,qw,qx,qy,qz\n1000000000,1,2,3,1,0,0,0\n1005000000,1,2,3,1,0\n");
  ExpectInputError([&] { EurocSequence::Open(Root()); },
                   {"state_groundtruth_estimate0/data.csv:3:", "8 fields", "found 6"});
  // A quaternion of zero length means no rotation; one of another length is normalised.
  WriteTextFile(path, "#t,x,y,z,qw,qx,qy,qz\n1000000000,1,2,3,0,0,0,0\n");
  ExpectInputError([&] { EurocSequence::Open(Root()); }, {"data.csv:2:", "zero length"});
  WriteTextFile(path, "#t,x,y,z,qw,qx,qy,qz\n1000000000,1,2,3,2,0,0,0\n");
  EXPECT_TRUE(EurocSequence::Open(Root()).ground_truth()[0].pose.linear().isIdentity(1e-12));
}

TEST_F(BrokenEurocTest, BadSensorYaml) {
  const std::string path = mav0_ + "/cam1/sensor.yaml";
  std::string yaml = ReadTextFile(path);
  yaml.replace(yaml.find("intrinsics:"), 11, "intrinsix:");
  WriteTextFile(path, yaml);
  ExpectInputError([&] { EurocSequence::Open(Root()); },
                   {"cam1/sensor.yaml", "missing key 'intrinsics'"});
  WriteTextFile(path, "T_BS: [1, 2\nresolution: [752, 480]\n");
  ExpectInputError([&] { EurocSequence::Open(Root()); }, {"cam1/sensor.yaml:"});
  WriteTextFile(path, ReadTextFile(mav0_ + "/cam0/sensor.yaml") + "\n");
  std::string equidistant = ReadTextFile(path);
  equidistant.replace(equidistant.find("radial-tangential"), 17, "equidistant");
  WriteTextFile(path, equidistant);
  ExpectInputError([&] { EurocSequence::Open(Root()); },
                   {"cam1/sensor.yaml:", "unsupported distortion_model 'equidistant'"});
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
