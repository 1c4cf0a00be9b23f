#include "stereo_fabmap_slam/pipeline/frame_record.h"

namespace stereo_fabmap_slam::pipeline {

std::string DescribeRelocalization(const relocalization::Relocalization& r) {
  return std::string(relocalization::RelocalizationStatusName(r.status)) +
         (r.keyframe_id >= 0 ? " against keyframe " + std::to_string(r.keyframe_id)
                             : std::string()) +
         ": " + r.reason;
}

void RecordRelocalization(const RelocalizationAnswer& answer, FrameRecord* record) {
  if (answer.already_joined) return;
  record->timing.relocalization_ms = answer.ms;
  record->relocalization = DescribeRelocalization(answer.result);
  record->relocalized = answer.result.success();
}

}  // namespace stereo_fabmap_slam::pipeline
