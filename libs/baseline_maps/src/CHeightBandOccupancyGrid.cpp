#include <gam/maps/IniFields.h>
#include <gam/maps/MapRegistry.h>
#include <gam/maps/ObservationAdapters.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/T3DPointsTo2DScanParams.h>
#include <mrpt/serialization/CArchive.h>

#include <sstream>
#include <stdexcept>

using namespace mrpt::maps;

MAP_DEFINITION_REGISTER("mrpt::maps::CHeightBandOccupancyGrid,heightBandGrid", mrpt::maps::CHeightBandOccupancyGrid)
IMPLEMENTS_SERIALIZABLE(CHeightBandOccupancyGrid, COccupancyGridMap2D, mrpt::maps)

namespace
{
// What tools need to know about this class (gam/maps/MapRegistry.h).
const bool kTraitsRegistered = [] {
	gam::maps::MapTraits t;
	t.className = "mrpt::maps::CHeightBandOccupancyGrid";
	t.sections = {
		{"_creationOpts", gam::maps::gridCreationKeys()},
		{"_insertOpts", {}},
		{"_likelihoodOpts", {}},
		{"_bandOpts", gam::maps::ini::keys<CHeightBandOccupancyGrid::THeightBandOptions>()}};
	t.writeOutputs = gam::maps::writeGridOutputs;
	t.keepWindow = gam::maps::keepGridWindow;
	t.startFromGrid = gam::maps::startGridFromStock;
	gam::maps::registerMapTraits(std::move(t));
	return true;
}();
}  // namespace

CHeightBandOccupancyGrid::TMapDefinition::TMapDefinition()
{
	// See the class comment: converted depth scans need these.
	insertionOpts.considerInvalidRangesAsFreeSpace = false;
	insertionOpts.horizontalTolerance = mrpt::DEG2RAD(10.0f);
}

void CHeightBandOccupancyGrid::TMapDefinition::loadFromConfigFile_map_specific(
	const mrpt::config::CConfigFileBase& source, const std::string& sectionNamePrefix)
{
	const std::string sC = sectionNamePrefix + "_creationOpts";
	gam::maps::ini::loadGridExtent(source, sC, min_x, max_x, min_y, max_y, resolution);
	insertionOpts.loadFromConfigFile(source, sectionNamePrefix + "_insertOpts");
	likelihoodOpts.loadFromConfigFile(source, sectionNamePrefix + "_likelihoodOpts");
	bandOpts.loadFromConfigFile(source, sectionNamePrefix + "_bandOpts");
}

void CHeightBandOccupancyGrid::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const
{
	out << "min_x=" << min_x << " max_x=" << max_x << " min_y=" << min_y << " max_y=" << max_y
		<< " resolution=" << resolution << "\n";
	insertionOpts.dumpToTextStream(out);
	likelihoodOpts.dumpToTextStream(out);
	bandOpts.dumpToTextStream(out);
}

mrpt::maps::CMetricMap* CHeightBandOccupancyGrid::internal_CreateFromMapDefinition(const TMetricMapInitializer& _def)
{
	const auto& def = dynamic_cast<const CHeightBandOccupancyGrid::TMapDefinition&>(_def);
	auto* m = new CHeightBandOccupancyGrid(def.min_x, def.max_x, def.min_y, def.max_y, def.resolution);
	m->insertionOptions = def.insertionOpts;
	m->likelihoodOptions = def.likelihoodOpts;
	m->bandOptions = def.bandOpts;
	return m;
}

// ---------------------------------------------------------------------------
void CHeightBandOccupancyGrid::THeightBandOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& source, const std::string& section)
{
	gam::maps::ini::loadThenCheck(*this, source, section, [this] { validate(); });
}

void CHeightBandOccupancyGrid::THeightBandOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& target, const std::string& section) const
{
	gam::maps::ini::save(*this, target, section);
}

void CHeightBandOccupancyGrid::THeightBandOptions::validate() const
{
	gam::checkParamRanges(*this, "bandOpts:");
	gam::requireParams(z_min < z_max, "bandOpts:", "z_min must be < z_max");
}

// ---------------------------------------------------------------------------
CHeightBandOccupancyGrid::CHeightBandOccupancyGrid(float min_x, float max_x, float min_y, float max_y, float resolution)
	: COccupancyGridMap2D(min_x, max_x, min_y, max_y, resolution)
{
	insertionOptions.considerInvalidRangesAsFreeSpace = false;
	insertionOptions.horizontalTolerance = mrpt::DEG2RAD(10.0f);
}

std::string CHeightBandOccupancyGrid::asString() const
{
	std::ostringstream s;
	s << "CHeightBandOccupancyGrid " << getSizeX() << "x" << getSizeY() << " cells at " << getResolution()
	  << " m, band z[" << bandOptions.z_min << "," << bandOptions.z_max << "]";
	return s.str();
}

mrpt::obs::T3DPointsTo2DScanParams CHeightBandOccupancyGrid::scanParams(const std::string& sensorLabel) const
{
	mrpt::obs::T3DPointsTo2DScanParams sp;
	sp.sensorLabel = sensorLabel;
	sp.use_origin_sensor_pose = true;
	sp.z_min = bandOptions.z_min;
	sp.z_max = bandOptions.z_max;
	sp.oversampling_ratio = bandOptions.oversampling_ratio;
	return sp;
}

bool CHeightBandOccupancyGrid::internal_insertObservation(
	const mrpt::obs::CObservation& obs, const std::optional<const mrpt::poses::CPose3D>& robotPose)
{
	using namespace mrpt::obs;
	const mrpt::poses::CPose3D pose = robotPose ? *robotPose : mrpt::poses::CPose3D();
	if (IS_CLASS(obs, CObservation3DRangeScan))
	{
		// convertTo2DScan() is non-const only because it caches lookup tables.
		auto& o3 = const_cast<CObservation3DRangeScan&>(dynamic_cast<const CObservation3DRangeScan&>(obs));
		if (!o3.hasRangeImage || o3.rangeImage.cols() == 0) return false;
		// MRPT trusts the intrinsics, image size and units: check them here.
		gam::maps::checkRangeScan(o3);
		gam::maps::checkScanGrowth(*this, pose + o3.sensorPose);
		m_lastScan = CObservation2DRangeScan();
		o3.convertTo2DScan(m_lastScan, scanParams(o3.sensorLabel));
		m_hasLastScan = true;
		if (m_lastScan.getScanSize() == 0) return false;
		m_lastScan = gam::maps::safeScanFor(*this, m_lastScan, pose);
		return COccupancyGridMap2D::internal_insertObservation(m_lastScan, robotPose);
	}
	if (const auto* o2 = dynamic_cast<const CObservation2DRangeScan*>(&obs))
		return COccupancyGridMap2D::internal_insertObservation(gam::maps::safeScanFor(*this, *o2, pose), robotPose);
	return COccupancyGridMap2D::internal_insertObservation(obs, robotPose);
}

// ---------------------------------------------------------------------------
// v0 = base grid (with its own version) + bandOptions as (key, value) pairs.
uint8_t CHeightBandOccupancyGrid::serializeGetVersion() const { return 0; }

void CHeightBandOccupancyGrid::serializeTo(mrpt::serialization::CArchive& out) const
{
	out << COccupancyGridMap2D::serializeGetVersion();
	COccupancyGridMap2D::serializeTo(out);
	gam::maps::ini::write(bandOptions, out);
}

void CHeightBandOccupancyGrid::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0: {
			uint8_t baseVer;
			in >> baseVer;
			COccupancyGridMap2D::serializeFrom(in, baseVer);
			gam::maps::ini::read(bandOptions, in, "CHeightBandOccupancyGrid");
			m_hasLastScan = false;
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}
