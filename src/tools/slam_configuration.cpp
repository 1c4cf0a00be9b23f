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

}  // namespace stereo_fabmap_slam::tools
