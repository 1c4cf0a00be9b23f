#pragma once

#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::backend {

struct BundleAdjustmentOptions {
  static constexpr char kSection[] = "backend";

  int window = 15;          // keyframes optimised together
  int fixed_keyframes = 1;  // the oldest keyframes of the window are held fixed (the gauge)
  int iterations = 10;      // Levenberg-Marquardt iterations a round
  int rounds = 2;           // optimise, remove outlier observations, optimise again
  double sigma = 1.0;       // [px] key point position noise
  int threads = 1;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;
};

}  // namespace stereo_fabmap_slam::backend
