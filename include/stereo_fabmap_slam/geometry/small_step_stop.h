#pragma once

#include <ceres/iteration_callback.h>

namespace stereo_fabmap_slam::geometry {

// Ends a Ceres solve after an accepted step that lowered the cost (half the sum of the squared,
// sigma-scaled residuals) by less than `decrease` [sigma^2]: a step of Mahalanobis length about
// sqrt(2 x decrease) under the problem's information. Where a problem converges fast (each
// step's decrease 20-100 times below the one before it, as bundle adjustment on the rendered hall)
// the step after such a step would change nothing the observations can tell apart, and Ceres' own
// rule (function_tolerance, relative to the cost) mostly rejects it anyway after paying for its
// linear solve; where it converges slowly, it ends the solve before that rule would.
// Only while every step so far was accepted: after a rejected one the trust region is smaller
// than the Gauss-Newton step, and a small decrease may say that the region was cut rather than
// that the optimum is near. One instance per solve.
class SmallStepStop final : public ceres::IterationCallback {
 public:
  explicit SmallStepStop(double decrease) : decrease_(decrease) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration == 0) return ceres::SOLVER_CONTINUE;  // the start: no step yet
    if (!summary.step_is_successful) {
      step_rejected_ = true;
      return ceres::SOLVER_CONTINUE;
    }
    return !step_rejected_ && summary.cost_change < decrease_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                                                              : ceres::SOLVER_CONTINUE;
  }

 private:
  double decrease_;
  bool step_rejected_ = false;
};

}  // namespace stereo_fabmap_slam::geometry
