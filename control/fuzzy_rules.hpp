// SPDX-License-Identifier: Apache-2.0
// Rule tables of the fuzzy gain scheduler, copied verbatim from SPEC §4 (UGV paper, dong2024,
// Tables 1-3). Rows: quantised error e, columns: quantised error change ec, both in the order
// NB NM NS ZO PS PM PB. Each entry names the output term of dKp, dKi or dKd.
#pragma once

#include <array>
#include <cstdint>

namespace weedspray::control {

// The seven linguistic terms, centred at -6 -4 -2 0 2 4 6 on the quantised domain.
enum class FuzzyTerm : std::uint8_t { NB, NM, NS, ZO, PS, PM, PB };

inline constexpr int kFuzzyTermCount = 7;

// Centre of a term on the domain [-6, 6].
constexpr double fuzzy_term_centre(FuzzyTerm term) {
  return 2.0 * (static_cast<int>(term) - 3);
}

using FuzzyRuleTable = std::array<std::array<FuzzyTerm, kFuzzyTermCount>, kFuzzyTermCount>;

namespace fuzzy_rule_terms {
inline constexpr FuzzyTerm NB = FuzzyTerm::NB;
inline constexpr FuzzyTerm NM = FuzzyTerm::NM;
inline constexpr FuzzyTerm NS = FuzzyTerm::NS;
inline constexpr FuzzyTerm ZO = FuzzyTerm::ZO;
inline constexpr FuzzyTerm PS = FuzzyTerm::PS;
inline constexpr FuzzyTerm PM = FuzzyTerm::PM;
inline constexpr FuzzyTerm PB = FuzzyTerm::PB;
}  // namespace fuzzy_rule_terms

// clang-format off
inline constexpr FuzzyRuleTable kDeltaKpRules = [] {
  using namespace fuzzy_rule_terms;
  return FuzzyRuleTable{{
      //      NB  NM  NS  ZO  PS  PM  PB   (ec)
      /*NB*/ {PB, PB, PM, PM, PS, ZO, ZO},
      /*NM*/ {PB, PB, PM, PS, PS, ZO, NS},
      /*NS*/ {PM, PM, PM, PS, ZO, NS, NS},
      /*ZO*/ {PM, PM, PS, ZO, NS, NM, NM},
      /*PS*/ {PS, PS, ZO, NS, NS, NM, NM},
      /*PM*/ {PS, ZO, NS, NM, NM, NM, NB},
      /*PB*/ {ZO, ZO, NM, NM, NM, NB, NB},
  }};
}();

inline constexpr FuzzyRuleTable kDeltaKiRules = [] {
  using namespace fuzzy_rule_terms;
  return FuzzyRuleTable{{
      //      NB  NM  NS  ZO  PS  PM  PB   (ec)
      /*NB*/ {NB, NB, NM, NM, NS, ZO, ZO},
      /*NM*/ {NB, NB, NM, NS, NS, ZO, ZO},
      /*NS*/ {NB, NM, NS, NS, ZO, PS, PS},
      /*ZO*/ {NM, NM, NS, ZO, PS, PM, PM},
      /*PS*/ {NM, NS, ZO, PS, PM, PM, PB},
      /*PM*/ {ZO, ZO, PS, PS, PM, PB, PB},
      /*PB*/ {ZO, ZO, PS, PM, PM, PB, PB},
  }};
}();

inline constexpr FuzzyRuleTable kDeltaKdRules = [] {
  using namespace fuzzy_rule_terms;
  return FuzzyRuleTable{{
      //      NB  NM  NS  ZO  PS  PM  PB   (ec)
      /*NB*/ {PS, NS, NB, NB, NB, NM, PS},
      /*NM*/ {PS, NS, NB, NM, NM, NS, ZO},
      /*NS*/ {ZO, NS, NM, NM, NS, NS, ZO},
      /*ZO*/ {ZO, NS, NS, NS, NS, NS, ZO},
      /*PS*/ {ZO, ZO, ZO, ZO, ZO, ZO, ZO},
      /*PM*/ {PB, NS, PS, PS, PS, PS, PB},
      /*PB*/ {PB, PM, PM, PM, PS, PS, PB},
  }};
}();
// clang-format on

}  // namespace weedspray::control
