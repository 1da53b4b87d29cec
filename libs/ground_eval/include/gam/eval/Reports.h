// Ground-aware mapping for MRPT -- map evaluation: the reports of the scores
// (text table, JSON, CSV). Pure C++17, no MRPT.
#pragma once

#include <string>
#include <vector>

#include "gam/eval/MapReaders.h"
#include "gam/eval/Scoring.h"

namespace gam::eval
{
/** The four categories of the report, in order. */
const std::vector<std::string>& reportCategories();

/** Human-readable table of several maps. */
std::string formatTable(const GroundTruth& gt, const std::vector<MapScore>& scores, const Options& opt);
/** JSON document with every number. */
std::string toJson(const GroundTruth& gt, const std::vector<MapScore>& scores, const Options& opt);
/** Flat CSV for aggregation: map,reading,record,id,category,n,occupied,free,unknown,detected
 * (record = object | floor | ramp | obstacle | ramp_object: one per ramp, id = its object). */
std::string toCsv(const std::vector<MapScore>& scores);

}  // namespace gam::eval
