// Ground-aware mapping for MRPT -- tests: the real rawlogs of ../shared/data/real
// (GAM_REAL_DATA_DIR, set by tests/CMakeLists.txt).
#pragma once

#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/system/filesystem.h>

#include <string>

namespace testdata
{
inline std::string realData(const std::string& rel) { return std::string(GAM_REAL_DATA_DIR) + "/" + rel; }

/** The first CObservation3DRangeScan of a real rawlog (images loaded), or null
 * if the file is missing or has none. */
inline mrpt::obs::CObservation3DRangeScan::Ptr firstScan(const std::string& rel)
{
	const std::string file = realData(rel);
	if (!mrpt::system::fileExists(file)) return {};
	mrpt::obs::CRawlog rl;
	if (!rl.loadFromRawLogFile(file)) return {};
	for (size_t i = 0; i < rl.size(); i++)
		if (rl.getType(i) == mrpt::obs::CRawlog::etObservation)
			if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(rl.getAsObservation(i)))
			{
				o->load();
				return o;
			}
	return {};
}
}  // namespace testdata
