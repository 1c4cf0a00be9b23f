#include "slam_configuration.h"

#include <set>

#include "stereo_fabmap_slam/io/options_file.h"

namespace stereo_fabmap_slam::tools {

SlamConfiguration SlamConfiguration::Load(const std::string& path) {
  const io::OptionsFile file = io::OptionsFile::Load(path);
  SlamConfiguration configuration;
  std::set<std::string> sections;
  configuration.ForEachModule([&](auto& options) {
    options = file.Read(options);
    sections.insert(options.kSection);
  });
  file.RejectUnknownSections(sections);
  return configuration;
}

void SlamConfiguration::Print(std::ostream& out) const {
  SlamConfiguration copy = *this;  // visiting takes mutable fields; printing changes nothing
  copy.ForEachModule([&](auto& options) { io::PrintOptions(options, out); });
}

place_recognition::PlaceRecognitionOptions SlamConfiguration::LoadPlaceRecognition(
    const std::string& path) {
  place_recognition::PlaceRecognitionOptions place =
      place_recognition::LoadPlaceRecognitionOptions(path, front_end.features);
  front_end.place_features = place.features;
  return place;
}

void SlamConfiguration::EnableLoopClosing(const place_recognition::PlaceRecognitionOptions& place,
                                          const camera::StereoRectifier& rectifier,
                                          pipeline::StereoSlam* slam) const {
  slam->EnableLoopClosing(
      pipeline::PlaceStage::LoadDetector(place, loop_detection, rectifier.camera(),
                                         slam->descriptor_norm(), slam->max_match_distance()),
      pose_graph, relocalization, global_refinement);
}

}  // namespace stereo_fabmap_slam::tools
