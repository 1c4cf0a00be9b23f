#pragma once

#include <array>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/place_recognition/chow_liu_tree.h"
#include "stereo_fabmap_slam/place_recognition/place_database.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"

namespace stereo_fabmap_slam::place_recognition {

// Per-word probabilities of the FAB-MAP observation model (Cummins & Newman, IJRR 2008): the
// detector model, the place appearance p(e | place) after a place's observations, and the
// observation likelihood of each word given its Chow-Liu parent.
class FabMapModel {
 public:
  FabMapModel(ChowLiuTree tree, double p_z_given_e, double p_z_given_not_e);

  // p(e_q = 1 | a place observed `observations` times, `hits` of them showing word q).
  double Theta(int q, int hits, int observations) const;
  double PriorTheta(int q) const { return tree_.Marginal(q); }
  // log p(z_q = z | z_parent = zp, place with p(e_q = 1) = theta) = log sum_e p(z | e, zp) p(e).
  double Term(int q, bool z, bool zp, double theta) const;
  // sum over all words of Term(q, 0, 0, .) for a place with no hits seen `observations` times,
  // or for the average place (prior): cached.
  double EmptySum(int observations) const;
  double PriorEmptySum() const { return prior_empty_sum_; }
  const ChowLiuTree& tree() const { return tree_; }
  int size() const { return tree_.size(); }

 private:
  ChowLiuTree tree_;
  double p_z_given_e_, p_z_given_not_e_;
  std::vector<std::array<double, 8>> z_given_e_zp_;  // [z * 4 + zp * 2 + e] = p(z | e, zp)
  double prior_empty_sum_ = 0;
  mutable std::map<int, double> empty_sums_;
};

struct FabMapResult {
  std::vector<double> posterior;  // per place in the map
  double new_place = 1.0;         // probability that the view shows a new place
  int best = -1;                  // place with the highest posterior, -1 if the map is empty
  // log(p(best | Z) / p(new place | Z)) before smoothing: how much likelier the view shows the
  // best place than a place not in the map. The smoothed posterior saturates: log-likelihoods
  // differ by tens of nats, so most confident answers read 0.99 + 0.01 / (places + 1) and their
  // order follows the map's size, not the evidence. Nor is the best weighed against the other
  // places: consecutive keyframes of one location share its posterior, and a true revisit would
  // look unsure exactly where the map is dense. Against the new place, each place stands on its
  // own evidence; perceptual aliasing is the new-place model's to explain (common words are
  // likely anywhere). Add() decides with it (match_log_odds), and the evaluation ranks by it;
  // loop detection orders one query's candidates by posterior, which is the same order.
  double best_log_odds = -std::numeric_limits<double>::infinity();
  std::vector<double> log_likelihoods;  // log p(Z | place)
  double new_place_log_likelihood = 0;  // log p(Z | new place)
  // Compare over candidates: log(p(candidate) / p(new place)) under its uniform prior, the same
  // for every candidate.
  double candidate_log_prior_odds = 0;

  // Compare over candidates: how much likelier the view shows candidate `place` than a new
  // place (best_log_odds for the best). Each candidate on its own evidence, unlike the
  // posterior, which saturates at the best one.
  double CandidateLogOdds(int place) const {
    return log_likelihoods[static_cast<std::size_t>(place)] - new_place_log_likelihood +
           candidate_log_prior_odds;
  }
};

// Where the odometry put a view's camera, for Add()'s place extent. Poses compare only within
// one odometry segment: after a tracking loss the odometry starts a frame unrelated to the last.
struct ViewPose {
  int segment = -1;  // -1: the odometry had no pose for the view (tracking lost)
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
};

// FAB-MAP: the posterior over the places in the map and a new place, given the words of a view.
// FAB-MAP 2.0 (the default) computes the same log-likelihoods as FAB-MAP 1.0 by rearranging the
// sum over words: a per-place constant plus corrections for the words the query shows (and their
// Chow-Liu children), found through the inverted index, so that a query costs time in
// proportion to the places sharing its words, not to places x vocabulary. The corrections are
// summed in single precision, which keeps the scores of 100,000 places in a core's L2 cache.
class FabMap {
 public:
  // `training_places`: the training images as places, for the sampling new-place model.
  FabMap(ChowLiuTree tree, const FabMapOptions& options,
         PlaceDatabase training_places = PlaceDatabase());

  FabMapResult Compare(const std::vector<int>& words) const;
  // Compare over a subset of the map: `candidates[i]` (one per place) says whether place i may
  // be the answer. The others get posterior 0 and no prior mass, as if they were not in the map,
  // so the result equals Compare on a map of the candidates alone (uniform location prior: the
  // motion prior follows Add's sequence, which a subset breaks). Loop detection leaves out the
  // recent past; relocalization leaves out the piece of map it is lost in.
  FabMapResult Compare(const std::vector<int>& words, const std::vector<char>& candidates) const;
  // Compare, then update the best place if its log odds reach match_log_odds, or add a new
  // place; `place` receives which. Appearance alone decides (image folders without odometry).
  FabMapResult Add(const std::vector<int>& words, int* place = nullptr);
  // The same with the view's odometry pose: only places founded in the same segment within
  // options.max_place_extent of it, looking no more than options.max_place_turn_deg away, may
  // take the view (the likeliest of those, if its log odds reach match_log_odds); a view
  // without a pose founds a place no view will update. The result is Compare's over the whole
  // map, whichever place took the view.
  FabMapResult Add(const std::vector<int>& words, const ViewPose& where, int* place = nullptr);

  // Adds the words as a new place, never merged with an existing one (the SLAM map keeps one
  // place per keyframe); returns its index.
  int AddPlace(const std::vector<int>& words);

  const PlaceDatabase& places() const { return places_.database; }
  // Replaces the map's places (e.g. loaded from a file).
  void SetPlaces(PlaceDatabase places);
  const FabMapModel& model() const { return model_; }

 private:
  struct IndexedPlaces {
    PlaceDatabase database;
    std::vector<double>
        hit_sums;  // per place: sum over its words of Term(hits) - Term(no hits), absent word
  };
  struct Query {
    std::vector<char> present;  // per word
    std::vector<int>
        affected;  // query words and their children: where the terms differ from "absent"
  };

  Query Prepare(const std::vector<int>& words) const;
  double HitSum(const Place& place) const;
  void Reindex(IndexedPlaces* places) const;
  std::vector<double> LogLikelihoods(const IndexedPlaces& places, const Query& query) const;
  std::vector<double> LogLikelihoodsFull(const IndexedPlaces& places, const Query& query) const;
  std::vector<double> LogLikelihoodsIndexed(const IndexedPlaces& places, const Query& query) const;
  double NewPlaceLogLikelihood(const Query& query) const;
  double FirstViewLogLikelihood(int place, const Query& query) const;
  // The place that takes the view: the best place if `eligible` (one flag per place) lets it,
  // else the likeliest eligible place, provided its log odds reach match_log_odds (and it
  // matches its first view, if so configured); -1: the view founds a new place.
  int PlaceToUpdate(const std::vector<int>& words, const FabMapResult& result,
                    const std::vector<char>& eligible) const;
  // Updates place `update` with the view, or adds it as a new place (update < 0).
  void Insert(const std::vector<int>& words, int update, int* place);

  FabMapOptions options_;
  FabMapModel model_;
  IndexedPlaces places_, samples_;
  std::vector<std::vector<int>> first_views_;  // per place: the words it was founded with
  // Per place: where its first view was taken from; nullopt for a place founded by Add without a
  // position (or loaded), which only Add without a position updates.
  std::vector<std::optional<ViewPose>> founded_at_;
  int last_match_ = -1;
};

}  // namespace stereo_fabmap_slam::place_recognition
