// The JSON of FORMATS.md ("leakmon model check"): cause, params, calibrated, ranking,
// nrmse_before, nrmse_after; extended with standard errors and the held-out significance.
#pragma once

#include <string>

#include "model/diagnosis.hpp"

namespace leakmon::model {

std::string diagnosis_json(const Diagnosis& diagnosis);

}  // namespace leakmon::model
