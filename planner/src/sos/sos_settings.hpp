#pragma once
// What the SOS stage works with: the user's options and the study settings in one struct, so
// the stage's steps read one place (sos_program.hpp, sos_program_study.hpp).

#include "flatsos/planner/sos_program.hpp"
#include "flatsos/planner/sos_program_study.hpp"

namespace flatsos::planner::detail {

struct BoundsSettings : ExcitationBoundsOptions, BoundsStudyOptions {};

struct SosSettings {
  int flat_output_degree = 4;
  int flat_output_spans = 1;
  double flat_output_span_growth = 1.0;
  SosProgramMethod method = SosProgramMethod::Exchange;
  WholeProgramOptions whole_program;
  double feasibility_margin_N = 1e-6;
  int max_exchange_rounds = 40;
  bool certify = true;
  double near_active_N = 1.0;
  ExchangeStudyOptions exchange;
  BoundsSettings bounds;
  std::shared_ptr<const Effort> effort;  // nonlinear; null: the map's linear effort
};

inline SosSettings sos_settings(const SosProgramOptions& options, const SosProgramStudyOptions& study) {
  SosSettings s;
  s.flat_output_degree = options.flat_output_degree;
  s.flat_output_spans = options.flat_output_spans;
  s.flat_output_span_growth = options.flat_output_span_growth;
  s.effort = options.effort;
  s.method = study.method;
  s.whole_program = study.whole_program;
  s.feasibility_margin_N = study.feasibility_margin_N;
  s.max_exchange_rounds = study.max_exchange_rounds;
  s.certify = study.certify;
  s.near_active_N = study.near_active_N;
  s.exchange = study.exchange;
  static_cast<ExcitationBoundsOptions&>(s.bounds) = options.bounds;
  static_cast<BoundsStudyOptions&>(s.bounds) = study.bounds;
  return s;
}

}  // namespace flatsos::planner::detail
