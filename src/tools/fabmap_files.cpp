#include "fabmap_files.h"

#include <filesystem>
#include <stdexcept>

namespace stereo_fabmap_slam::tools {

FabMapFiles LoadFabMapFiles(const std::string& vocabulary_file) {
  const std::string directory = std::filesystem::path(vocabulary_file).parent_path().string();
  if (directory.empty()) throw std::runtime_error("--vocabulary must name a file in a folder");
  return {directory, place_recognition::Vocabulary::Load(vocabulary_file),
          place_recognition::ChowLiuTree::Load(directory + "/chow_liu_tree.bin"),
          place_recognition::PlaceDatabase::Load(directory + "/training_places.bin")};
}

}  // namespace stereo_fabmap_slam::tools
