#include "stereo_fabmap_slam/place_recognition/fab_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace stereo_fabmap_slam::place_recognition {
namespace {

double LogSumExp(const std::vector<double>& values) {
  const double top = *std::max_element(values.begin(), values.end());
  double sum = 0;
  for (const double v : values) sum += std::exp(v - top);
  return top + std::log(sum);
}

}  // namespace

FabMapModel::FabMapModel(ChowLiuTree tree, double p_z_given_e, double p_z_given_not_e)
    : tree_(std::move(tree)), p_z_given_e_(p_z_given_e), p_z_given_not_e_(p_z_given_not_e) {
  const int v = tree_.size();
  z_given_e_zp_.resize(static_cast<std::size_t>(v));
  for (int q = 0; q < v; ++q) {
    for (int z = 0; z < 2; ++z) {
      for (int zp = 0; zp < 2; ++zp) {
        for (int e = 0; e < 2; ++e) {
          // p(z_q | e_q, z_p) combining the detector model and the tree (Cummins & Newman 2008):
          // with e and z_p independent given z, Bayes gives
          // p(z | e, z_p) proportional to p(z | e) p(z | z_p) / p(z), so alpha / (alpha + beta)
          // with alpha = p(not z) p(z | e) p(z | z_p) and beta the same for not z. Where the
          // parent tells nothing (p(z | z_p) = p(z)) this is the detector model itself.
          const auto detector = [&](bool seen) {
            const double p_seen = e ? p_z_given_e_ : p_z_given_not_e_;
            return seen ? p_seen : 1.0 - p_seen;
          };
          const double marginal = tree_.Marginal(q);
          const double alpha =
              (z ? 1 - marginal : marginal) * detector(z) * tree_.Conditional(q, z, zp);
          const double beta =
              (z ? marginal : 1 - marginal) * detector(!z) * tree_.Conditional(q, !z, zp);
          z_given_e_zp_[static_cast<std::size_t>(q)][z * 4 + zp * 2 + e] = alpha / (alpha + beta);
        }
      }
    }
    prior_empty_sum_ += Term(q, false, false, PriorTheta(q));
  }
}

double FabMapModel::Theta(int q, int hits, int observations) const {
  // Bayes: prior p(obs | e) / (prior p(obs | e) + (1 - prior) p(obs | not e)), divided through
  // by p(obs | e) > 0. The likelihood ratio is the same for every word.
  const double absent_over_present =
      std::pow(p_z_given_not_e_ / p_z_given_e_, hits) *
      std::pow((1 - p_z_given_not_e_) / (1 - p_z_given_e_), observations - hits);
  const double prior = PriorTheta(q);
  return prior / (prior + (1 - prior) * absent_over_present);
}

double FabMapModel::Term(int q, bool z, bool zp, double theta) const {
  const std::array<double, 8>& p = z_given_e_zp_[static_cast<std::size_t>(q)];
  const int base = (z ? 4 : 0) + (zp ? 2 : 0);
  return std::log(p[base + 1] * theta + p[base] * (1 - theta));
}

double FabMapModel::EmptySum(int observations) const {
  const auto cached = empty_sums_.find(observations);
  if (cached != empty_sums_.end()) return cached->second;
  double sum = 0;
  for (int q = 0; q < size(); ++q) sum += Term(q, false, false, Theta(q, 0, observations));
  empty_sums_[observations] = sum;
  return sum;
}

FabMap::FabMap(ChowLiuTree tree, const FabMapOptions& options, PlaceDatabase training_places)
    : options_((options.Validate(), options)),
      model_(std::move(tree), options.p_z_given_e, options.p_z_given_not_e) {
  places_.database = PlaceDatabase(model_.size());
  samples_.database = std::move(training_places);
  if (samples_.database.vocabulary_size() != 0 &&
      samples_.database.vocabulary_size() != model_.size()) {
    throw std::invalid_argument("training places and Chow-Liu tree have different vocabularies");
  }
  if (options_.new_place_model == NewPlaceModel::kSampling && samples_.database.size() == 0) {
    throw std::invalid_argument("the sampling new-place model needs training places");
  }
  Reindex(&samples_);
}

void FabMap::SetPlaces(PlaceDatabase places) {
  if (places.vocabulary_size() != model_.size()) {
    throw std::invalid_argument("places and Chow-Liu tree have different vocabularies");
  }
  places_.database = std::move(places);
  Reindex(&places_);
  // A loaded place's first view is not stored: the place as a whole stands for it.
  first_views_.clear();
  for (int i = 0; i < places_.database.size(); ++i) {
    const std::vector<std::int32_t>& words = places_.database.place(i).words;
    first_views_.emplace_back(words.begin(), words.end());
  }
  founded_at_.assign(first_views_.size(), std::nullopt);
  last_match_ = -1;
}

double FabMap::HitSum(const Place& place) const {
  double sum = 0;
  for (std::size_t i = 0; i < place.words.size(); ++i) {
    const int q = place.words[i];
    sum += model_.Term(q, false, false, model_.Theta(q, place.hits[i], place.observations)) -
           model_.Term(q, false, false, model_.Theta(q, 0, place.observations));
  }
  return sum;
}

void FabMap::Reindex(IndexedPlaces* places) const {
  places->hit_sums.resize(static_cast<std::size_t>(places->database.size()));
  for (int i = 0; i < places->database.size(); ++i)
    places->hit_sums[i] = HitSum(places->database.place(i));
}

FabMap::Query FabMap::Prepare(const std::vector<int>& words) const {
  Query query;
  query.present.assign(static_cast<std::size_t>(model_.size()), 0);
  for (const int w : words) {
    if (w < 0 || w >= model_.size()) throw std::invalid_argument("word outside the vocabulary");
    query.present[static_cast<std::size_t>(w)] = 1;
  }
  // FAB-MAP 1.0 and exact 2.0 see every absent child of a view's word with its parent present.
  const bool children = !options_.inverted_index || options_.exact_tree_corrections;
  for (const int w : words) {
    query.affected.push_back(w);
    if (!children) continue;
    for (const int child : model_.tree().children(w)) {
      if (!query.present[static_cast<std::size_t>(child)]) query.affected.push_back(child);
    }
  }
  std::sort(query.affected.begin(), query.affected.end());
  query.affected.erase(std::unique(query.affected.begin(), query.affected.end()),
                       query.affected.end());
  return query;
}

std::vector<double> FabMap::LogLikelihoodsFull(const IndexedPlaces& places,
                                               const Query& query) const {
  // FAB-MAP 1.0: every word of the vocabulary for every place.
  const ChowLiuTree& tree = model_.tree();
  std::vector<double> result;
  for (int i = 0; i < places.database.size(); ++i) {
    const Place& place = places.database.place(i);
    double sum = 0;
    std::size_t next = 0;
    for (int q = 0; q < model_.size(); ++q) {
      int hits = 0;
      if (next < place.words.size() && place.words[next] == q) hits = place.hits[next++];
      const bool z = query.present[static_cast<std::size_t>(q)];
      const bool zp =
          tree.parent(q) >= 0 && query.present[static_cast<std::size_t>(tree.parent(q))];
      sum += model_.Term(q, z, zp, model_.Theta(q, hits, place.observations));
    }
    result.push_back(sum);
  }
  return result;
}

std::vector<double> FabMap::LogLikelihoodsIndexed(const IndexedPlaces& places,
                                                  const Query& query) const {
  // FAB-MAP 2.0: log p(Z | L) = [sum_q Term(q, 0, 0, theta_0)] + [corrections for the affected
  // words, same for every place observed as often] + hit_sums[L] + [corrections for affected
  // words the place has shown, found through the inverted index]. A word's correction depends on
  // the place only through (hits, observations), so it is one constant per posting list.
  const ChowLiuTree& tree = model_.tree();
  const PlaceDatabase& database = places.database;
  // Per affected word: its state in the query.
  struct Affected {
    int word;
    bool z, zp;
  };
  std::vector<Affected> affected;
  affected.reserve(query.affected.size());
  for (const int u : query.affected) {
    affected.push_back(
        {u, query.present[static_cast<std::size_t>(u)] != 0,
         tree.parent(u) >= 0 && query.present[static_cast<std::size_t>(tree.parent(u))]});
  }
  // What an affected word shown in `hits` of a place's `observations` adds to its log-likelihood.
  const auto change = [&](const Affected& a, int hits, int observations) {
    const double with = model_.Theta(a.word, hits, observations);
    const double without = model_.Theta(a.word, 0, observations);
    return (model_.Term(a.word, a.z, a.zp, with) - model_.Term(a.word, a.z, a.zp, without)) -
           (model_.Term(a.word, false, false, with) - model_.Term(a.word, false, false, without));
  };
  std::vector<double> once;  // change(a, 1, 1): the same for every place seen once
  once.reserve(affected.size());
  for (const Affected& a : affected) once.push_back(change(a, 1, 1));

  // The hot path, one addition per posting: every place is scored as if seen once. Single
  // precision halves the scores' cache footprint (100,000 places fit a core's L2 cache); a
  // place sums a few hundred changes, and the rounding stays within 1e-6 of its log-likelihood
  // (the tests' bound against FAB-MAP 1.0; 1.5e-7 seen).
  std::vector<float> scores(static_cast<std::size_t>(database.size()), 0.0F);
  std::size_t next = 0;
  for (; next + 1 < affected.size(); next += 2) {
    PostingList::AddTo(database.PlacesWith(affected[next].word), static_cast<float>(once[next]),
                       database.PlacesWith(affected[next + 1].word),
                       static_cast<float>(once[next + 1]), scores.data());
  }
  if (next < affected.size()) {
    database.PlacesWith(affected[next].word).AddTo(static_cast<float>(once[next]), scores.data());
  }

  // Places observed more than once change the sum by their own amounts, not by `once`: one
  // constant per affected word and group, added through the groups' own postings into an array
  // of the repeated places, then moved to their scores.
  const std::vector<std::int32_t>& repeated = database.repeated_places();
  if (!repeated.empty()) {
    std::vector<float> corrections(repeated.size(), 0.0F);
    for (std::size_t k = 0; k < affected.size(); ++k) {
      for (const RepeatedGroup& group : database.RepeatedWith(affected[k].word)) {
        const double own = change(affected[k], group.hits, group.observations);
        group.ranks.AddTo(static_cast<float>(own - once[k]), corrections.data());
      }
    }
    for (std::size_t r = 0; r < repeated.size(); ++r)
      scores[static_cast<std::size_t>(repeated[r])] += corrections[r];
  }

  // The part of the sum shared by all places observed equally often: computed once per distinct
  // observation count (almost always just one).
  std::map<int, double> common;  // by number of observations
  const auto shared = [&](int n) {
    auto it = common.find(n);
    if (it != common.end()) return it->second;
    double sum = model_.EmptySum(n);
    for (const Affected& a : affected) {
      const double theta = model_.Theta(a.word, 0, n);
      sum += model_.Term(a.word, a.z, a.zp, theta) - model_.Term(a.word, false, false, theta);
    }
    return common.emplace(n, sum).first->second;
  };
  const std::vector<std::int32_t>& observations = database.observations();
  std::vector<double> result(scores.size());
  int last_n = -1;
  double last_shared = 0;
  for (std::size_t i = 0; i < scores.size(); ++i) {
    const int n = observations[i];
    if (n != last_n) {
      last_n = n;
      last_shared = shared(n);
    }
    result[i] = last_shared + places.hit_sums[i] + static_cast<double>(scores[i]);
  }
  return result;
}

std::vector<double> FabMap::LogLikelihoods(const IndexedPlaces& places, const Query& query) const {
  return options_.inverted_index ? LogLikelihoodsIndexed(places, query)
                                 : LogLikelihoodsFull(places, query);
}

double FabMap::NewPlaceLogLikelihood(const Query& query) const {
  if (options_.new_place_model == NewPlaceModel::kSampling) {
    // The average likelihood of the training images taken as places.
    std::vector<double> samples = LogLikelihoods(samples_, query);
    return LogSumExp(samples) - std::log(static_cast<double>(samples.size()));
  }
  // Mean field: a place whose every word has its prior probability.
  const ChowLiuTree& tree = model_.tree();
  double sum = model_.PriorEmptySum();
  for (const int u : query.affected) {
    const bool z = query.present[static_cast<std::size_t>(u)];
    const bool zp = tree.parent(u) >= 0 && query.present[static_cast<std::size_t>(tree.parent(u))];
    sum += model_.Term(u, z, zp, model_.PriorTheta(u)) -
           model_.Term(u, false, false, model_.PriorTheta(u));
  }
  return sum;
}

FabMapResult FabMap::Compare(const std::vector<int>& words) const {
  const Query query = Prepare(words);
  FabMapResult result;
  result.log_likelihoods = LogLikelihoods(places_, query);
  result.new_place_log_likelihood = NewPlaceLogLikelihood(query);
  const int n = static_cast<int>(result.log_likelihoods.size());
  if (n == 0) return result;

  // Location prior: the new place gets new_place_prior; the rest is spread over the places,
  // uniformly or, with the motion model, partly on the last match and its neighbours. Only the
  // neighbours differ from the rest, so the logarithm is taken once for the others.
  const double existing = 1 - options_.new_place_prior;
  std::vector<double> log_joint(result.log_likelihoods);
  if (options_.location_prior == LocationPrior::kMotion && last_match_ >= 0) {
    const int first = std::max(0, last_match_ - 1), last = std::min(n - 1, last_match_ + 1);
    const double spread = existing * (1 - options_.motion_weight) / n;
    const double near = spread + existing * options_.motion_weight / (last - first + 1);
    const double log_spread = std::log(spread);
    for (int i = 0; i < n; ++i) log_joint[i] += log_spread;
    for (int i = first; i <= last; ++i) log_joint[i] = result.log_likelihoods[i] + std::log(near);
  } else {
    const double log_uniform = std::log(existing / n);
    for (double& l : log_joint) l += log_uniform;
  }
  log_joint.push_back(result.new_place_log_likelihood + std::log(options_.new_place_prior));
  result.best = static_cast<int>(std::max_element(log_joint.begin(), log_joint.end() - 1) -
                                 log_joint.begin());
  result.best_log_odds = log_joint[static_cast<std::size_t>(result.best)] - log_joint.back();
  // Normalise, with one exponential per place: p_i = exp(l_i - top) / sum_j exp(l_j - top).
  // log_joint becomes the unnormalised joint exp(l_i - top).
  const double top = *std::max_element(log_joint.begin(), log_joint.end());
  double sum = 0;
  for (double& l : log_joint) {
    l = std::exp(l - top);
    sum += l;
  }
  const double uniform = (1 - options_.smoothing) / (n + 1);
  const double scale = options_.smoothing / sum;
  result.posterior.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) result.posterior[i] = scale * log_joint[i] + uniform;
  result.new_place = scale * log_joint.back() + uniform;
  return result;
}

FabMapResult FabMap::Compare(const std::vector<int>& words,
                             const std::vector<char>& candidates) const {
  if (static_cast<int>(candidates.size()) != places_.database.size()) {
    throw std::invalid_argument("FabMap::Compare: " + std::to_string(candidates.size()) +
                                " candidate flags for " + std::to_string(places_.database.size()) +
                                " places");
  }
  const Query query = Prepare(words);
  FabMapResult result;
  result.log_likelihoods = LogLikelihoods(places_, query);
  result.new_place_log_likelihood = NewPlaceLogLikelihood(query);
  const int places = static_cast<int>(result.log_likelihoods.size());
  result.posterior.assign(static_cast<std::size_t>(places), 0.0);
  const int n = static_cast<int>(std::count(candidates.begin(), candidates.end(), char{1}));
  if (n == 0) return result;

  // As Compare with a uniform prior, over the candidates only.
  const double log_uniform = std::log((1 - options_.new_place_prior) / n);
  const double log_new = result.new_place_log_likelihood + std::log(options_.new_place_prior);
  result.candidate_log_prior_odds = log_uniform - std::log(options_.new_place_prior);
  // The candidates' log joints go into `posterior` first and are exponentiated in place: no
  // second array of the map's size on the query path.
  double top = log_new;
  for (int i = 0; i < places; ++i) {
    if (!candidates[i]) continue;
    result.posterior[i] = result.log_likelihoods[i] + log_uniform;
    if (result.best < 0 || result.posterior[i] > result.posterior[result.best]) result.best = i;
    top = std::max(top, result.posterior[i]);
  }
  result.best_log_odds = result.posterior[static_cast<std::size_t>(result.best)] - log_new;
  double sum = 0;
  for (int i = 0; i < places; ++i) {
    if (!candidates[i]) continue;
    result.posterior[i] = std::exp(result.posterior[i] - top);
    sum += result.posterior[i];
  }
  const double new_joint = std::exp(log_new - top);
  sum += new_joint;
  const double uniform = (1 - options_.smoothing) / (n + 1);
  const double scale = options_.smoothing / sum;
  for (int i = 0; i < places; ++i) {
    if (candidates[i]) result.posterior[i] = scale * result.posterior[i] + uniform;
  }
  result.new_place = scale * new_joint + uniform;
  return result;
}

int FabMap::AddPlace(const std::vector<int>& words) {
  const int index = places_.database.AddPlace(words);
  places_.hit_sums.push_back(HitSum(places_.database.place(index)));
  first_views_.push_back(words);
  founded_at_.emplace_back();
  return index;
}

double FabMap::FirstViewLogLikelihood(int place, const Query& query) const {
  IndexedPlaces first;
  first.database = PlaceDatabase(model_.size());
  first.database.AddPlace(first_views_[static_cast<std::size_t>(place)]);
  first.hit_sums.push_back(HitSum(first.database.place(0)));
  return LogLikelihoods(first, query).front();
}

int FabMap::PlaceToUpdate(const std::vector<int>& words, const FabMapResult& result,
                          const std::vector<char>& eligible) const {
  if (result.best < 0) return -1;
  // The best place when it may take the view, with its log odds as Compare gave them (location
  // prior included); otherwise the likeliest of those that may, with the best's prior (the
  // uniform prior gives every place the same): the same test, whichever place is best.
  int best = result.best;
  double log_odds = result.best_log_odds;
  if (!eligible[static_cast<std::size_t>(best)]) {
    const std::size_t overall = static_cast<std::size_t>(result.best);
    best = -1;
    for (std::size_t i = 0; i < eligible.size(); ++i) {
      if (eligible[i] && (best < 0 || result.log_likelihoods[i] >
                                          result.log_likelihoods[static_cast<std::size_t>(best)]))
        best = static_cast<int>(i);
    }
    if (best < 0) return -1;
    log_odds = result.best_log_odds + result.log_likelihoods[static_cast<std::size_t>(best)] -
               result.log_likelihoods[overall];
  }
  if (log_odds < options_.match_log_odds) return -1;
  if (options_.update_near_first_view) {
    // The same log odds with the place's first view in place of the place.
    const double first = FirstViewLogLikelihood(best, Prepare(words));
    if (log_odds + first - result.log_likelihoods[static_cast<std::size_t>(best)] <
        options_.match_log_odds)
      return -1;
  }
  return best;
}

void FabMap::Insert(const std::vector<int>& words, int update, int* place) {
  int index;
  if (update >= 0) {
    index = update;
    places_.database.UpdatePlace(index, words);
    places_.hit_sums[static_cast<std::size_t>(index)] = HitSum(places_.database.place(index));
  } else {
    index = AddPlace(words);
  }
  last_match_ = index;
  if (place != nullptr) *place = index;
}

FabMapResult FabMap::Add(const std::vector<int>& words, int* place) {
  FabMapResult result = Compare(words);
  // Places founded with a position belong to Add with positions; appearance alone decides
  // among the others.
  std::vector<char> eligible(founded_at_.size());
  for (std::size_t i = 0; i < founded_at_.size(); ++i) eligible[i] = !founded_at_[i];
  Insert(words, PlaceToUpdate(words, result, eligible), place);
  return result;
}

FabMapResult FabMap::Add(const std::vector<int>& words, const ViewPose& where, int* place) {
  FabMapResult result = Compare(words);
  std::vector<char> eligible(founded_at_.size(), 0);
  if (where.segment >= 0) {
    const double min_axis_cosine = std::cos(options_.max_place_turn_deg * M_PI / 180.0);
    const Eigen::Vector3d axis = where.T_world_camera.linear().col(2);
    for (std::size_t i = 0; i < founded_at_.size(); ++i) {
      const std::optional<ViewPose>& founded = founded_at_[i];
      eligible[i] =
          founded && founded->segment == where.segment &&
          (founded->T_world_camera.translation() - where.T_world_camera.translation()).norm() <=
              options_.max_place_extent &&
          founded->T_world_camera.linear().col(2).dot(axis) >= min_axis_cosine;
    }
  }
  const int update = PlaceToUpdate(words, result, eligible);
  Insert(words, update, place);
  if (update < 0) founded_at_.back() = where;
  return result;
}

}  // namespace stereo_fabmap_slam::place_recognition
