#include "detect/legacy_state.hpp"

#include "detect/feature_test.hpp"
#include "detect/flow_law_ladder.hpp"

#include <cmath>
#include <initializer_list>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace leakmon::detect {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Reads an old state's entries, checked as the old build checked them, into a new one.
class Conversion {
 public:
  Conversion(const DetectorState& old, int version) : old_(old), out_(old.kind(), version) {}

  const std::vector<double>& list(std::string_view key, std::size_t size) const {
    const auto& values = old_.get_list(key);
    if (values.size() != size) throw StateError("'" + std::string(key) + "' has the wrong length");
    return values;
  }
  const std::vector<double>& list(std::string_view key) const { return old_.get_list(key); }
  double get(std::string_view key) const { return old_.get(key); }
  std::size_t count(std::string_view key) const { return old_.get_count(key); }

  DetectorState& out() { return out_; }
  void put(std::string_view key, double value) { out_.put(key, value); }
  void put(std::string_view key, std::span<const double> values) { out_.put(key, values); }
  // The same entry under a new name.
  void rename(std::string_view from, std::string_view to) { out_.put(to, old_.get_list(from)); }
  // A list's values under one name each.
  void split(std::string_view from, std::string_view prefix,
             std::initializer_list<std::string_view> names) {
    const auto& values = list(from, names.size());
    std::size_t i = 0;
    for (const auto name : names) out_.put(state_key(prefix, name), values[i++]);
  }
  // Records of `names.size()` values each, flat in `values`, as one list per field.
  void columns(std::span<const double> values, std::string_view prefix,
               std::initializer_list<std::string_view> names) {
    const std::size_t width = names.size();
    if (values.size() % width != 0) {
      throw StateError("'" + std::string(prefix) + "' is not a whole number of records");
    }
    std::vector<double> column(values.size() / width);
    std::size_t field = 0;
    for (const auto name : names) {
      for (std::size_t i = 0; i < column.size(); ++i) column[i] = values[i * width + field];
      out_.put(state_key(prefix, name), column);
      ++field;
    }
  }
  // A ring saved as all its slots with `next` and `count` (the old layout): its filled slots,
  // which until it is full are the first `count`, as Ring's save_ring() lays them out.
  void ring(std::span<const double> slots, std::size_t next, std::size_t count,
            std::string_view prefix, std::initializer_list<std::string_view> names) {
    const std::size_t width = names.size();
    if (slots.size() % width != 0) {
      throw StateError("'" + std::string(prefix) + "' is not a whole number of records");
    }
    const std::size_t capacity = slots.size() / width;
    if (next >= std::max<std::size_t>(capacity, 1) || count > capacity) {
      throw StateError("'" + std::string(prefix) + "' position out of range");
    }
    columns(slots.first(count * width), prefix, names);
    out_.put_count(state_key(prefix, "next"), next);
    out_.put_count(state_key(prefix, "capacity"), capacity);
  }

 private:
  const DetectorState& old_;
  DetectorState out_;
};

// flow_balance 2 -> 3.
DetectorState flow_from_2(const DetectorState& old) {
  Conversion c(old, 3);
  c.put("learning.hops_seen", static_cast<double>(c.count("hops_seen")));
  c.rename("learned_model", "learning.learned");
  c.put("observations", static_cast<double>(c.count("observations")));
  c.rename("previous_x", "previous_x");
  for (const char* hop : {"before", "pending"}) {
    c.split(hop, hop,
            {"t", "opening", "load", "root", "leak_term", "speed", "supply", "viscosity_ratio",
             "usable"});
  }
  c.columns(c.list("learned_rest_hops"), "learned",
            {"t", "opening", "load", "root", "leak_term", "speed", "supply", "viscosity_ratio",
             "usable", "block"});
  c.split("positive_loads", "positive_loads", {"low", "high", "middle"});
  c.split("negative_loads", "negative_loads", {"low", "high", "middle"});
  c.split("coefficients", "coefficient",
          {"constant", "side", "leak_term", "side_leak_term", "curvature_positive",
           "curvature_negative"});
  c.rename("hop_sigma", "hop_sigma");
  c.rename("block_sigma", "block_sigma");
  c.put("block.hops", static_cast<double>(c.count("block_hop")));
  c.put("block.rest_hops", static_cast<double>(c.count("block_rest_hops")));
  c.split("block_sums", "block", {"residual_sum", "leak_term_sum"});
  c.split("weighted", "sizing.weighted", {"rl", "ll", "ll_sq"});
  c.split("since_change", "sizing.since_change", {"rl", "ll", "ll_sq"});
  c.split("change_block", "sizing.change_block", {"rl", "ll", "ll_sq"});
  c.put("cusum.value", c.get("cusum"));
  c.split("last_decision", "last",
          {"score", "learning", "baseline", "index", "leak_coefficient", "leak_coefficient_ci",
           "viscosity_ratio"});
  // The supply's estimate and the time its last step began (the transient's start).
  const auto& supply = c.list("supply", 2);
  c.put("supply.estimate", supply[0]);
  c.put("supply.anchor", kNaN);
  c.put("supply.step_time", supply[1]);
  c.put("supply.off_readings", 0.0);
  c.rename("temperature_seen", "temperature_seen");
  c.ring(c.list("trend"), c.count("trend_next"), c.count("trend_count"), "drift",
         {"t", "residual", "scale"});
  return c.out();
}

// flow_balance 3 -> 4: the excitation and judging entries. No learned rest loads: the state
// judges at every load, as the build that wrote it did.
DetectorState flow_from_3(const DetectorState& old) {
  DetectorState out(old.kind(), 4);
  for (const auto& entry : old.entries()) out.put(entry.first, entry.second);
  out.put("block.load_sum", 0.0);
  out.put_count("block.unsettled_hops", 0);
  out.put("rest_loads.low", kNaN);
  out.put("rest_loads.high", kNaN);
  out.put_count("excitation.wait_hops", 0);
  out.put("excitation.cannot_learn", 0.0);
  out.put("judging.last_judged_t", kNaN);
  out.put("judging.reason", static_cast<double>(NotJudgedReason::in_motion));
  return out;
}

// flow_law 1 integrated the flow with the stated spool time constant only: layout 2's ladder
// with that one chosen (every candidate holds its values, only the chosen is read again).
DetectorState flow_law_from_1(const DetectorState& old) {
  constexpr std::size_t kCandidates = kTauCandidates;
  DetectorState out(old.kind(), 2);
  for (const auto& entry : old.entries()) {
    if (entry.first != "spool.opening" && entry.first != "sample.flow" &&
        entry.first != "block.flow") {
      out.put(entry.first, entry.second);
    }
  }
  const auto ladder = [&](std::string_view from, std::string_view to) {
    const std::vector<double> values(kCandidates, old.get(from));
    out.put(to, values);
  };
  ladder("spool.opening", "spool.openings");
  ladder("sample.flow", "sample.flows");
  ladder("block.flow", "block.flows");
  std::vector<double> y_tau;
  for (const double y : old.get_list("learned.y")) y_tau.insert(y_tau.end(), kCandidates, y);
  out.put("learned.y_tau", y_tau);
  out.put("tau.index", static_cast<double>(kStatedTau));
  out.put("tau.fit_lag", 0.0);
  out.put("coefficient.lag", 0.0);
  out.put("learned.lag", std::vector<double>(old.get_list("learned.y").size(), 0.0));
  return out;
}

// flow_law 2 read the supply at every hop at rest, sized from every block since its CUSUM left
// zero and kept no blocks of the run. Layout 3 counts the hops at rest first: counted as long at
// rest, the converted state reads as the old build did until the piston next moves. Without the
// run, the sums since the change are those of the old build; the run fills from the next block
// the CUSUM judges.
DetectorState flow_law_from_2(const DetectorState& old) {
  DetectorState out(old.kind(), 3);
  for (const auto& entry : old.entries()) out.put(entry.first, entry.second);
  out.put("still_hops", 1e6);
  return out;
}

// flow_law 3 did not tell the learning blocks at rest from those that move (issue 23's wait for
// excitation): its blocks load as moving, as does its block in progress (no fastest hop), so a
// converted state waiting for excitation waits until motion identifies the load term or new
// blocks at rest cover the loads. A state that had learned judges as it did.
DetectorState flow_law_from_3(const DetectorState& old) {
  DetectorState out(old.kind(), 4);
  for (const auto& entry : old.entries()) out.put(entry.first, entry.second);
  out.put("learned.moving", std::vector<double>(old.get_list("learned.t").size(), 1.0));
  out.put("block.max_speed", kNaN);
  return out;
}

// flow_law 4 had no null-offset regressor (the valve's bias). A state that had learned judges as
// it did (coefficient 0). A state still learning keeps its blocks without the regressor and learns
// without it, as the build that wrote it would (`null_offset.fit` 0, until the next reset); one
// with no learning block yet fits it, and its block in progress, whose integral of the
// regressor is missing, is not used.
DetectorState flow_law_from_4(const DetectorState& old) {
  DetectorState out(old.kind(), 5);
  for (const auto& entry : old.entries()) out.put(entry.first, entry.second);
  const std::size_t blocks = old.get_list("learned.t").size();
  const bool learned = old.get("learning.learned") != 0.0;
  out.put("learned.null_offset", std::vector<double>(blocks, 0.0));
  out.put("coefficient.null_offset", 0.0);
  out.put("null_offset.fit", blocks > 0 && !learned ? 0.0 : 1.0);
  out.put("sample.null_offset_gain", 0.0);
  out.put("block.null_offset", 0.0);
  if (!learned && blocks == 0) out.put("block.ok", 0.0);
  return out;
}

// flow_law 5 kept no learned range: it loads without one and judges every block, as its build
// did (a state learned again after a reset keeps the range).
DetectorState flow_law_from_5(const DetectorState& old) {
  DetectorState out(old.kind(), 6);
  for (const auto& entry : old.entries()) out.put(entry.first, entry.second);
  out.put("range.inverse_normal", std::vector<double>(36, 0.0));
  out.put("range.max_leverage", kNaN);
  out.put("range.outside_blocks", 0.0);
  return out;
}

// flow_law 6 read the supply at rest only: it loads reading it so, as its build did (a reset
// reads it in motion too).
DetectorState flow_law_from_6(const DetectorState& old) {
  DetectorState out(old.kind(), 7);
  for (const auto& entry : old.entries()) out.put(entry.first, entry.second);
  out.put("supply_motion.sum", 0.0);
  out.put("supply_motion.hops", 0.0);
  out.put("supply_motion.read", 0.0);
  return out;
}

// flow_law 7 had no tank-offset regressor (the stated tank pressure's error). As layout 4's null
// offset: a state that had learned judges as it did (coefficient 0, the column left out: its
// learned range gains an axis of its own, decoupled, that no block reaches); one still learning
// keeps its blocks and learns without it until the next reset; one with no learning block yet
// fits it, its block in progress not used.
DetectorState flow_law_from_7(const DetectorState& old) {
  DetectorState out(old.kind(), 8);
  for (const auto& entry : old.entries()) out.put(entry.first, entry.second);
  const std::size_t blocks = old.get_list("learned.t").size();
  const bool learned = old.get("learning.learned") != 0.0;
  out.put("learned.tank_offset", std::vector<double>(blocks, 0.0));
  out.put("coefficient.tank_offset", 0.0);
  out.put("tank_offset.fit", blocks > 0 || learned ? 0.0 : 1.0);
  out.put("sample.tank_offset_gain", 0.0);
  out.put("block.tank_offset", 0.0);
  if (!learned && blocks == 0) out.put("block.ok", 0.0);
  const auto& inverse = old.get_list("range.inverse_normal");
  if (inverse.size() != 36) throw StateError("'range.inverse_normal' has the wrong length");
  std::vector<double> padded(49, 0.0);
  for (std::size_t column = 0; column < 6; ++column) {
    for (std::size_t row = 0; row < 6; ++row) padded[column * 7 + row] = inverse[column * 6 + row];
  }
  padded[48] = 1.0;
  out.put("range.inverse_normal", padded);
  return out;
}

// One chamber's supply tracker: 17 values by position, then its holds' ring.
void chamber_supply_from_positions(Conversion& c, const std::vector<double>& v,
                                   std::string_view prefix) {
  constexpr std::size_t kFixed = 17;
  if (v.size() < kFixed || (v.size() - kFixed) % 2 != 0) {
    throw StateError("chamber supply: wrong number of values");
  }
  auto count = [&](std::size_t i, double limit) {
    if (!(v[i] >= 0.0 && v[i] <= limit) || v[i] != std::floor(v[i])) {
      throw StateError("chamber supply: a count out of range");
    }
    return static_cast<std::size_t>(v[i]);
  };
  const std::size_t capacity = (v.size() - kFixed) / 2;
  const std::size_t next = count(0, static_cast<double>(capacity) - 1.0);
  const std::size_t filled = count(1, static_cast<double>(capacity));
  const std::size_t still = count(2, static_cast<double>(std::size_t{1} << 40));
  const std::size_t used = count(3, static_cast<double>(still));
  const std::size_t pending = count(16, 2.0);
  c.ring(std::span<const double>(v).subspan(kFixed), next, filled, state_key(prefix, "holds"),
         {"t", "level"});
  c.put(state_key(prefix, "hold.still_hops"), static_cast<double>(still));
  c.put(state_key(prefix, "hold.used_hops"), static_cast<double>(used));
  const std::initializer_list<std::pair<std::size_t, std::string_view>> named = {
      {4, "hold.sum"},    {5, "hold.last_t"}, {6, "hold.start"},      {7, "learned_mid"},
      {8, "near"},        {9, "far"},         {10, "learned_offset"}, {11, "mid"},
      {12, "last_fit_t"}, {13, "step_time"},  {14, "awaiting_since"}, {15, "awaiting_from_t"}};
  for (const auto& [i, name] : named) c.put(state_key(prefix, name), v[i]);
  c.put(state_key(prefix, "pending"), static_cast<double>(pending));
}

// index_cusum 3 -> 4. Its `learned_log_supply` and `block_temps` were never computed: dropped
// (block_temps still has to be a position in the block, as 3 required).
DetectorState index_from_3(const DetectorState& old) {
  Conversion c(old, 4);
  c.put("learning.hops_seen", static_cast<double>(c.count("hops_seen")));
  c.rename("learned_model", "learning.learned");
  c.columns(c.list("learned_blocks"), "learned",
            {"t", "feature", "load", "load_squared", "log_activity", "log_friction", "log_supply"});
  c.split("coefficients", "coefficient",
          {"constant", "load", "load_squared", "log_activity", "log_friction"});
  c.get("learned_log_supply");
  c.rename("block_sigma", "block_sigma");
  c.put("block.hops", static_cast<double>(c.count("block_hop")));
  c.put("block.valid", static_cast<double>(c.count("block_valid")));
  if (c.count("block_temps") > c.count("block_hop")) {
    throw StateError("block position out of range");
  }
  c.split("block_sums", "block",
          {"sum_feature", "sum_load", "sum_load_squared", "sum_activity", "sum_log_friction",
           "sum_log_supply"});
  c.rename("previous_load", "previous_load");
  c.rename("previous_rough_load", "previous_rough_load");
  c.rename("last_expected", "last_expected");
  c.rename("temperature_seen", "temperature_seen");
  c.split("supply", "supply", {"estimate", "anchor", "step_time"});
  c.put("supply.off_readings", static_cast<double>(c.count("supply_off_hops")));
  chamber_supply_from_positions(c, c.list("chamber_supply"), "chamber_supply");
  c.rename("learned_supply", "learned_supply");
  c.put("cusum.value", c.get("cusum"));
  c.ring(c.list("cusum_history"), c.count("cusum_next"), c.count("cusum_count"), "cusum.history",
         {"t", "before"});
  // The index's reference is a level (scale 1 per block).
  const auto& trend = c.list("trend");
  std::vector<double> scaled;
  scaled.reserve(trend.size() / 2 * 3);
  for (std::size_t i = 0; i + 1 < trend.size(); i += 2) {
    scaled.insert(scaled.end(), {trend[i], trend[i + 1], 1.0});
  }
  if (trend.size() % 2 != 0) throw StateError("'trend' is not a whole number of records");
  c.ring(scaled, c.count("trend_next"), c.count("trend_count"), "drift",
         {"t", "residual", "scale"});
  return c.out();
}

// paper 1 -> 2.
DetectorState paper_from_1(const DetectorState& old) {
  Conversion c(old, 2);
  c.put("learning.hops_seen", static_cast<double>(c.count("hops_seen")));
  c.put("learning.learned", std::isnan(c.get("baseline")) ? 0.0 : 1.0);
  c.rename("learned", "learned");
  c.rename("baseline", "baseline");
  const auto& below = c.list("below");
  std::size_t count = 0;
  for (const double v : below) {
    if (v != 0.0 && v != 1.0) throw StateError("verdict not 0 or 1");
    count += v != 0.0 ? 1 : 0;
  }
  if (count != c.count("below_count")) throw StateError("verdict count differs");
  c.ring(below, c.count("ring_next"), c.count("ring_filled"), "window", {"below"});
  return c.out();
}

// detail_xcorr 1 -> 2: its test was an index_cusum 3 state under "test.".
DetectorState xcorr_from_1(const DetectorState& old) {
  Conversion c(old, 2);
  const DetectorState test = upgraded_state(old.get_nested("test"), "index_cusum", 4);
  for (const auto& [key, values] : test.entries()) c.put(state_key("test", key), values);
  c.rename("history_a", "history_a");
  c.rename("history_b", "history_b");
  c.put("primed", static_cast<double>(c.count("primed")));
  // The window's hops, oldest first from the slot after the newest; the filled ones last.
  const auto& hops = c.list("hops");
  if (hops.size() % 5 != 0 || hops.empty()) throw StateError("'hops' is not whole hops");
  const std::size_t window = hops.size() / 5, filled = c.count("hops_filled");
  if (filled > window) throw StateError("filter position out of range");
  // In the ring they fill the slots from the first, oldest first.
  c.columns(std::span<const double>(hops).subspan(5 * (window - filled)), "hops",
            {"aa", "bb", "ab", "e1", "e3"});
  c.out().put_count("hops.next", filled % window);
  c.out().put_count("hops.capacity", window);
  c.rename("last_t", "last_t");
  return c.out();
}

// The feature test before issue 23 (index_cusum 4, detail_xcorr 2 under "test."): no
// excitation column, no regime model, no wait. The converted test judges as that build did:
// the regime model is unknown (every block judged) and learning does not wait.
DetectorState feature_test_from_issue_26(const DetectorState& old, int version,
                                         std::string_view prefix) {
  Conversion c(old, version);
  for (const auto& [key, values] : old.entries()) c.put(key, values);
  const auto key = [prefix](std::string_view name) { return state_key(prefix, name); };
  const std::size_t learned = c.list(key("learned.t")).size();
  c.put(key("learned.rest_share"), std::vector<double>(learned, kNaN));
  c.put(key("regime.rest_low"), kNaN);
  c.put(key("regime.rest_high"), kNaN);
  c.put(key("regime.blocks.t"), std::span<const double>());
  c.put(key("regime.blocks.share"), std::span<const double>());
  c.put(key("regime.blocks.residual"), std::span<const double>());
  c.out().put_count(key("regime.blocks.next"), 0);
  c.out().put_count(key("regime.blocks.capacity"), FeatureTest::kRegimeBlocks);
  c.put(key("regime.outside"), 0.0);
  c.put(key("excitation.wait_seconds"), 0.0);
  c.put(key("excitation.cannot_learn"), 0.0);
  c.put(key("excitation.waits"), 0.0);
  c.out().put_count(key("block.rest_hops"), 0);
  return c.out();
}

// The feature test before the run test (index_cusum 5, detail_xcorr 3): no learned runs, so
// the converted test tells the regime by the rest share alone, as that build did.
DetectorState feature_test_from_rest_share(const DetectorState& old, int version,
                                           std::string_view prefix) {
  Conversion c(old, version);
  for (const auto& [key, values] : old.entries()) c.put(key, values);
  const auto key = [prefix](std::string_view name) { return state_key(prefix, name); };
  c.put(key("regime.longest_rest"), kNaN);
  c.put(key("regime.longest_motion"), kNaN);
  for (const char* count : {"run.rest_hops", "run.motion_hops", "block.rest_run",
                            "block.motion_run", "excitation.rest_run", "excitation.motion_run"}) {
    c.out().put_count(key(count), 0);
  }
  return c.out();
}

// The feature test before its threshold followed the learned spread (detail_xcorr 4, and
// before it 1-3 once converted to 4): it keeps
// Lorden's threshold, and so decides as that build did.
DetectorState feature_test_from_lorden(const DetectorState& old, int version,
                                       std::string_view prefix) {
  Conversion c(old, version);
  for (const auto& [key, values] : old.entries()) c.put(key, values);
  c.put(state_key(prefix, "threshold.siegmund"), 0.0);
  return c.out();
}

// The feature test before it learned other programs (index_cusum 6, detail_xcorr 5, and the
// layouts before once converted to them): no other regime, and it learns none, so it judges as
// that build did (the first program only). The regime ring's blocks have no activity.
DetectorState feature_test_from_one_regime(const DetectorState& old, int version,
                                           std::string_view prefix) {
  Conversion c(old, version);
  for (const auto& [key, values] : old.entries()) c.put(key, values);
  const auto key = [prefix](std::string_view name) { return state_key(prefix, name); };
  const std::size_t ring = c.list(key("regime.blocks.t")).size();
  c.put(key("regime.blocks.activity"), std::vector<double>(ring, kNaN));
  for (const char* field :
       {"constant", "load", "load_squared", "log_activity", "sigma", "reference", "rest_low",
        "rest_high", "activity_low", "activity_high", "longest_rest", "longest_motion"}) {
    c.put(key(std::string("others.") + field), std::span<const double>());
  }
  c.put(key("others.judging"), -1.0);
  c.put(key("others.learns"), 0.0);
  for (const char* field : {"t", "feature", "load", "load_squared", "log_activity", "log_friction",
                            "log_supply", "rest_share"}) {
    c.put(key(std::string("others.candidate.") + field), std::span<const double>());
  }
  c.out().put_count(key("others.candidate_rest_run"), 0);
  c.out().put_count(key("others.candidate_motion_run"), 0);
  return c.out();
}

// The feature test before it read the load's reversal rate (index_cusum 7, detail_xcorr 6, and
// the layouts before once converted to them): its blocks and learned programs have none, so a
// program it learned is told as that build told it (rest share, activity and runs), and its
// drift reference slides on across a gap in its blocks as that build's did.
DetectorState feature_test_from_no_reversals(const DetectorState& old, int version,
                                             std::string_view prefix) {
  Conversion c(old, version);
  for (const auto& [key, values] : old.entries()) c.put(key, values);
  const auto key = [prefix](std::string_view name) { return state_key(prefix, name); };
  const auto none_for = [&](std::string_view list, std::string_view like) {
    c.put(key(list), std::vector<double>(c.list(key(like)).size(), kNaN));
  };
  none_for("learned.reversal_rate", "learned.t");
  none_for("others.candidate.reversal_rate", "others.candidate.t");
  none_for("regime.blocks.reversals", "regime.blocks.t");
  none_for("others.reversals_low", "others.constant");
  none_for("others.reversals_high", "others.constant");
  c.out().put_count(key("block.reversals"), 0);
  c.put(key("run.direction"), 0.0);
  c.put(key("drift_holds_across_gaps"), 0.0);
  return c.out();
}

}  // namespace

DetectorState upgraded_state(const DetectorState& state, std::string_view kind, int version) {
  if (state.kind() == kind && state.version() == version) return state;
  if (state.kind() == kind && kind == "index_cusum" && version == 8 && state.version() < 8) {
    return feature_test_from_no_reversals(upgraded_state(state, kind, 7), 8, "");
  }
  if (state.kind() == kind && kind == "detail_xcorr" && version == 7 && state.version() < 7) {
    return feature_test_from_no_reversals(upgraded_state(state, kind, 6), 7, "test");
  }
  if (state.kind() == kind && kind == "index_cusum" && version == 7 && state.version() < 7) {
    return feature_test_from_one_regime(upgraded_state(state, kind, 6), 7, "");
  }
  if (state.kind() == kind && kind == "detail_xcorr" && version == 6 && state.version() < 6) {
    return feature_test_from_one_regime(upgraded_state(state, kind, 5), 6, "test");
  }
  if (state.kind() == kind && kind == "detail_xcorr" && version == 5 && state.version() < 5) {
    return feature_test_from_lorden(upgraded_state(state, kind, 4), 5, "test");
  }
  if (state.kind() == kind) {
    if (kind == "flow_balance" && state.version() == 2 && version == 3) return flow_from_2(state);
    if (kind == "flow_balance" && state.version() == 2 && version == 4) {
      return flow_from_3(flow_from_2(state));
    }
    if (kind == "flow_balance" && state.version() == 3 && version == 4) return flow_from_3(state);
    if (kind == "index_cusum" && state.version() == 3 && version == 4) return index_from_3(state);
    if (kind == "index_cusum" && state.version() == 3 && version == 6) {
      return feature_test_from_rest_share(feature_test_from_issue_26(index_from_3(state), 5, ""), 6,
                                          "");
    }
    if (kind == "index_cusum" && state.version() == 4 && version == 6) {
      return feature_test_from_rest_share(feature_test_from_issue_26(state, 5, ""), 6, "");
    }
    if (kind == "index_cusum" && state.version() == 5 && version == 6) {
      return feature_test_from_rest_share(state, 6, "");
    }
    if (kind == "detail_xcorr" && state.version() == 1 && version == 4) {
      return feature_test_from_rest_share(
          feature_test_from_issue_26(xcorr_from_1(state), 3, "test"), 4, "test");
    }
    if (kind == "detail_xcorr" && state.version() == 2 && version == 4) {
      return feature_test_from_rest_share(feature_test_from_issue_26(state, 3, "test"), 4, "test");
    }
    if (kind == "detail_xcorr" && state.version() == 3 && version == 4) {
      return feature_test_from_rest_share(state, 4, "test");
    }
    if (kind == "paper" && state.version() == 1 && version == 2) return paper_from_1(state);
    if (kind == "flow_law" && state.version() < 8 && version == 8) {
      return flow_law_from_7(upgraded_state(state, kind, 7));
    }
    if (kind == "flow_law" && state.version() < 7 && version == 7) {
      return flow_law_from_6(upgraded_state(state, kind, 6));
    }
    if (kind == "flow_law" && state.version() < 6 && version == 6) {
      return flow_law_from_5(upgraded_state(state, kind, 5));
    }
    if (kind == "flow_law" && state.version() < 5 && version == 5) {
      return flow_law_from_4(upgraded_state(state, kind, 4));
    }
    if (kind == "flow_law" && state.version() < 4 && version == 4) {
      return flow_law_from_3(upgraded_state(state, kind, 3));
    }
    if (kind == "flow_law" && state.version() == 1 && version == 3) {
      return flow_law_from_2(flow_law_from_1(state));
    }
    if (kind == "flow_law" && state.version() == 2 && version == 3) return flow_law_from_2(state);
    if (kind == "detail_xcorr" && state.version() == 1 && version == 2) return xcorr_from_1(state);
  }
  state.expect(kind, version);  // throws: another kind, or a layout not read here
  return state;
}

bool has_learned(const DetectorState& state) {
  for (const auto& entry : state.entries()) {
    // Not a structured binding: Clang before 16 cannot capture one in a lambda.
    const std::string& key = entry.first;
    const std::vector<double>& values = entry.second;
    if (values.size() != 1) continue;
    const auto named = [&key](std::string_view name) {
      return key == name || (key.size() > name.size() && key.ends_with(name) &&
                             key[key.size() - name.size() - 1] == '.');
    };
    // This build's layouts: the learning clock; before: a fitted model. A baseline: paper.
    if ((named("learning.learned") || named("learned_model")) && values[0] != 0.0) return true;
    if (named("baseline") && !std::isnan(values[0])) return true;
  }
  return false;
}

}  // namespace leakmon::detect
