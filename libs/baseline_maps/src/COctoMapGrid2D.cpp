#include <gam/maps/GridIO.h>
#include <gam/maps/IniFields.h>
#include <gam/maps/MapRegistry.h>
#include <gam/maps/ObservationAdapters.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/COctoMapGrid2D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/opengl/COctoMapVoxels.h>
#include <mrpt/serialization/CArchive.h>

#include <fcntl.h>
#include <unistd.h>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

using namespace mrpt::maps;

MAP_DEFINITION_REGISTER("mrpt::maps::COctoMapGrid2D,octoMapGrid", mrpt::maps::COctoMapGrid2D)
IMPLEMENTS_SERIALIZABLE(COctoMapGrid2D, COccupancyGridMap2D, mrpt::maps)

namespace
{
// The 3D octomap itself, in OctoMap's own format (octovis, octomap tools).
// liboctomap prints "Writing N nodes..." on stderr: keep the tool's stderr clean.
void writeOctomapQuietly(const mrpt::maps::COctoMap& octo, const std::string& prefix)
{
	std::cerr.flush();
	std::fflush(stderr);
	const int saved = dup(2);
	const int devnull = open("/dev/null", O_WRONLY);
	if (devnull >= 0) dup2(devnull, 2);
	auto restore = [&] {
		std::cerr.flush();
		std::fflush(stderr);
		if (saved >= 0) dup2(saved, 2), close(saved);
		if (devnull >= 0) close(devnull);
	};
	try
	{
		octo.saveMetricMapRepresentationToFile(prefix);
	}
	catch (...)
	{
		restore();
		throw;
	}
	restore();
}

// What tools need to know about this class (gam/maps/MapRegistry.h).
const bool kTraitsRegistered = [] {
	gam::maps::MapTraits t;
	t.className = "mrpt::maps::COctoMapGrid2D";
	t.sections = {
		{"_creationOpts", gam::maps::gridCreationKeys()},
		{"_octoOpts", gam::maps::ini::keys<COctoMapGrid2D::TOctoOptions>()}};
	t.writeOutputs = [](CMetricMap& m, const gam::maps::OutputContext& ctx, std::vector<std::string>& files) {
		auto& oc = dynamic_cast<COctoMapGrid2D&>(m);
		if (oc.projectionOutdated()) oc.updateProjection();
		gam::maps::writeGridOutputs(oc, ctx, files);
		const std::string base = ctx.dir + "/" + ctx.label;
		writeOctomapQuietly(oc.octomap(), base + "_octomap");
		for (const char* ext : {"_octomap_binary.bt", "_octomap_3D.3Dscene"})
			if (std::filesystem::exists(base + ext)) files.push_back(ctx.label + ext);
	};
	t.stageTimes = [](const CMetricMap& m, bool, const gam::maps::StageSink& sink) {
		const auto& oc = dynamic_cast<const COctoMapGrid2D&>(m);
		sink("octomap_insert", oc.lastInsertionMs());
		sink("projection", oc.lastProjectionMs());
	};
	t.keepWindow = gam::maps::keepGridWindow;
	gam::maps::registerMapTraits(std::move(t));
	return true;
}();
}  // namespace

COctoMapGrid2D::TMapDefinition::TMapDefinition() = default;

void COctoMapGrid2D::TMapDefinition::loadFromConfigFile_map_specific(
	const mrpt::config::CConfigFileBase& source, const std::string& sectionNamePrefix)
{
	const std::string sC = sectionNamePrefix + "_creationOpts";
	gam::maps::ini::loadGridExtent(source, sC, min_x, max_x, min_y, max_y, resolution);
	octoOpts.loadFromConfigFile(source, sectionNamePrefix + "_octoOpts");
}

void COctoMapGrid2D::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const
{
	out << "min_x=" << min_x << " max_x=" << max_x << " min_y=" << min_y << " max_y=" << max_y
		<< " resolution=" << resolution << "\n";
	octoOpts.dumpToTextStream(out);
}

mrpt::maps::CMetricMap* COctoMapGrid2D::internal_CreateFromMapDefinition(const TMetricMapInitializer& _def)
{
	const auto& def = dynamic_cast<const COctoMapGrid2D::TMapDefinition&>(_def);
	auto* m = new COctoMapGrid2D(def.min_x, def.max_x, def.min_y, def.max_y, def.resolution);
	m->octoOptions = def.octoOpts;
	m->applyOctoOptions();
	return m;
}

// ---------------------------------------------------------------------------
void COctoMapGrid2D::TOctoOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& source, const std::string& section)
{
	gam::maps::ini::loadThenCheck(*this, source, section, [this] { validate(); });
}

void COctoMapGrid2D::TOctoOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& target, const std::string& section) const
{
	gam::maps::ini::save(*this, target, section);
}

void COctoMapGrid2D::TOctoOptions::validate() const
{
	gam::checkParamRanges(*this, "octoOpts:");
	gam::requireParams(z_min < z_max, "octoOpts:", "z_min must be < z_max");
	gam::requireParams(clamping_min < clamping_max, "octoOpts:", "clamping_min must be < clamping_max");
}

// ---------------------------------------------------------------------------
COctoMapGrid2D::COctoMapGrid2D(float min_x, float max_x, float min_y, float max_y, float resolution)
	: COccupancyGridMap2D(min_x, max_x, min_y, max_y, resolution), m_octomap(0.05)
{
	applyOctoOptions();
}

void COctoMapGrid2D::applyOctoOptions()
{
	octoOptions.validate();
	if (std::abs(m_octomap.getResolution() - octoOptions.voxel_size) > 1e-9)
		m_octomap = COctoMap(octoOptions.voxel_size);
	auto& io = m_octomap.insertionOptions;
	io.maxrange = octoOptions.max_range;
	io.pruning = true;
	io.setProbHit(octoOptions.prob_hit);
	io.setProbMiss(octoOptions.prob_miss);
	io.setClampingThresMin(octoOptions.clamping_min);
	io.setClampingThresMax(octoOptions.clamping_max);
	io.setOccupancyThres(octoOptions.occupancy_thres);
	m_octomap.renderingOptions.generateGridLines = false;
	m_octomap.renderingOptions.generateOccupiedVoxels = true;
	m_octomap.renderingOptions.generateFreeVoxels = true;
}

std::string COctoMapGrid2D::asString() const
{
	std::ostringstream s;
	s << "COctoMapGrid2D " << getSizeX() << "x" << getSizeY() << " cells at " << getResolution() << " m; octomap voxel "
	  << m_octomap.getResolution() << " m, " << m_octomap.getNumLeafNodes() << " leaves; band z[" << octoOptions.z_min
	  << "," << octoOptions.z_max << "]";
	return s.str();
}

void COctoMapGrid2D::internal_clear()
{
	COccupancyGridMap2D::internal_clear();
	m_octomap.clear();
	m_dirty = false;
	m_sinceProjection = 0;
}

namespace
{
int largestDivisorAtMost(int d, int w, int h)
{
	for (int k = std::max(1, d); k > 1; k--)
		if (w % k == 0 && h % k == 0) return k;
	return 1;
}
}  // namespace

bool COctoMapGrid2D::internal_insertObservation(
	const mrpt::obs::CObservation& obs, const std::optional<const mrpt::poses::CPose3D>& robotPose)
{
	using namespace mrpt::obs;
	const auto t0 = std::chrono::steady_clock::now();
	const mrpt::poses::CPose3D pose = robotPose ? *robotPose : mrpt::poses::CPose3D();
	for (double v : {pose.x(), pose.y(), pose.z(), pose.yaw(), pose.pitch(), pose.roll()})
		if (!std::isfinite(v)) throw std::invalid_argument("robot pose is not finite");
	bool inserted = false;
	if (IS_CLASS(obs, CObservation3DRangeScan))
	{
		const auto& o3 = dynamic_cast<const CObservation3DRangeScan&>(obs);
		if (!o3.hasRangeImage && !o3.hasPoints3D) return false;
		// MRPT's unprojectInto() trusts the intrinsics, image size and units: check them here.
		gam::maps::checkRangeScan(o3);
		mrpt::maps::CSimplePointsMap pts;
		pts.insertionOptions.minDistBetweenLaserPoints = 0;
		if (o3.hasRangeImage)
		{
			// unprojectInto() resizes the source's points3D vectors: work on a copy.
			CObservation3DRangeScan tmp = o3;
			tmp.hasPoints3D = false;
			T3DPointsProjectionParams pp;
			pp.takeIntoAccountSensorPoseOnRobot = true;
			pp.robotPoseInTheWorld = pose;
			pp.decimation = uint8_t(
				largestDivisorAtMost(octoOptions.decimation, int(tmp.rangeImage.cols()), int(tmp.rangeImage.rows())));
			tmp.unprojectInto(pts, pp);
		}
		else
		{
			const mrpt::poses::CPose3D sensorInMap = pose + o3.sensorPose;
			const size_t step = size_t(std::max(1, octoOptions.decimation));
			for (size_t i = 0; i < o3.points3D_x.size(); i += step)
			{
				double gx, gy, gz;
				sensorInMap.composePoint(o3.points3D_x[i], o3.points3D_y[i], o3.points3D_z[i], gx, gy, gz);
				if (!std::isfinite(gx) || !std::isfinite(gy) || !std::isfinite(gz)) continue;
				pts.insertPoint(float(gx), float(gy), float(gz));
			}
		}
		if (pts.size() == 0) return false;
		const mrpt::poses::CPose3D sensorInMap = pose + o3.sensorPose;
		// OctoMap keys cover +-32768 voxels per axis; liboctomap drops rays from
		// outside (one stderr warning per point): refuse such a pose clearly.
		const double reach = 32768.0 * m_octomap.getResolution() - octoOptions.max_range;
		if (std::abs(sensorInMap.x()) > reach || std::abs(sensorInMap.y()) > reach || std::abs(sensorInMap.z()) > reach)
		{
			std::ostringstream msg;
			msg << "sensor position (" << sensorInMap.x() << ", " << sensorInMap.y() << ", " << sensorInMap.z()
				<< ") is too large for the octomap: it covers +-" << reach << " m at voxel_size "
				<< m_octomap.getResolution() << " (minus max_range)";
			throw std::invalid_argument(msg.str());
		}
		m_octomap.insertPointCloud(pts, float(sensorInMap.x()), float(sensorInMap.y()), float(sensorInMap.z()));
		inserted = true;
	}
	else
		inserted = m_octomap.insertObservation(obs, robotPose);
	m_lastInsertMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
	if (!inserted) return false;
	m_dirty = true;
	m_sinceProjection++;
	if (octoOptions.project_every > 0 && m_sinceProjection >= octoOptions.project_every)
		updateProjection();
	else
		m_lastProjectionMs = 0;
	return true;
}

void COctoMapGrid2D::updateProjection()
{
	const auto t0 = std::chrono::steady_clock::now();
	m_sinceProjection = 0;
	m_dirty = false;
	// On the heap: COctoMapVoxels is over-aligned (32 bytes, Eigen members) and a
	// stack instance is not always aligned (UBSan: misaligned member call).
	const auto voxPtr = mrpt::opengl::COctoMapVoxels::Create();
	auto& vox = *voxPtr;
	m_octomap.renderingOptions.generateFreeVoxels = octoOptions.mark_free;
	m_octomap.getAsOctoMapVoxels(vox);
	const double zlo = octoOptions.z_min, zhi = octoOptions.z_max;
	using mrpt::opengl::VOXEL_SET_FREESPACE;
	using mrpt::opengl::VOXEL_SET_OCCUPIED;

	// Grow the grid to the footprint of every voxel in the band.
	float x0 = getXMin(), x1 = getXMax(), y0 = getYMin(), y1 = getYMax();
	bool grow = false;
	for (size_t set : {size_t(VOXEL_SET_OCCUPIED), size_t(VOXEL_SET_FREESPACE)})
	{
		if (set >= vox.getVoxelSetCount()) continue;
		for (size_t i = 0; i < vox.getVoxelCount(set); i++)
		{
			const auto& v = vox.getVoxel(set, i);
			const double h = 0.5 * v.side_length;
			if (v.coords.z + h <= zlo || v.coords.z - h >= zhi) continue;
			if (v.coords.x - h < x0 || v.coords.x + h > x1 || v.coords.y - h < y0 || v.coords.y + h > y1)
			{
				x0 = std::min(x0, float(v.coords.x - h));
				x1 = std::max(x1, float(v.coords.x + h));
				y0 = std::min(y0, float(v.coords.y - h));
				y1 = std::max(y1, float(v.coords.y + h));
				grow = true;
			}
		}
	}
	if (grow)
	{
		// Octomap keys span 65536 voxels per axis: far poses could need a huge 2D grid.
		gam::maps::checkGridSize("projecting the octomap", x0, x1, y0, y1, getResolution());
		resizeGrid(x0, x1, y0, y1, 0.5f, false);
	}
	fill(0.5f);

	const int sx = int(getSizeX()), sy = int(getSizeY());
	const float res = getResolution();
	auto paint = [&](const mrpt::opengl::COctoMapVoxels::TVoxel& v, cellType value) {
		const double h = 0.5 * v.side_length;
		// Cells whose centre lies in the voxel footprint (at least the one under the centre).
		int cx0 = int(std::ceil((v.coords.x - h - getXMin()) / res - 0.5));
		int cx1 = int(std::floor((v.coords.x + h - getXMin()) / res - 0.5));
		int cy0 = int(std::ceil((v.coords.y - h - getYMin()) / res - 0.5));
		int cy1 = int(std::floor((v.coords.y + h - getYMin()) / res - 0.5));
		if (cx1 < cx0) cx0 = cx1 = x2idx(v.coords.x);
		if (cy1 < cy0) cy0 = cy1 = y2idx(v.coords.y);
		for (int cy = std::max(0, cy0); cy <= std::min(sy - 1, cy1); cy++)
			for (int cx = std::max(0, cx0); cx <= std::min(sx - 1, cx1); cx++)
			{
				cellType& c = m_map[size_t(cx) + size_t(cy) * size_t(sx)];
				if (value < 0 || c == 0) c = value;  // occupied wins over free
			}
	};
	if (octoOptions.mark_free && VOXEL_SET_FREESPACE < vox.getVoxelSetCount())
		for (size_t i = 0; i < vox.getVoxelCount(VOXEL_SET_FREESPACE); i++)
		{
			const auto& v = vox.getVoxel(VOXEL_SET_FREESPACE, i);
			const double h = 0.5 * v.side_length;
			if (v.coords.z + h <= zlo || v.coords.z - h >= zhi) continue;
			paint(v, OCCGRID_CELLTYPE_MAX);
		}
	if (VOXEL_SET_OCCUPIED < vox.getVoxelSetCount())
		for (size_t i = 0; i < vox.getVoxelCount(VOXEL_SET_OCCUPIED); i++)
		{
			const auto& v = vox.getVoxel(VOXEL_SET_OCCUPIED, i);
			if (v.coords.z < zlo || v.coords.z > zhi) continue;  // octomap_server: centre in band
			paint(v, OCCGRID_CELLTYPE_MIN);
		}
	m_is_empty = false;
	m_likelihoodCacheOutDated = true;
	m_lastProjectionMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void COctoMapGrid2D::saveMetricMapRepresentationToFile(const std::string& prefix) const
{
	if (m_dirty) const_cast<COctoMapGrid2D*>(this)->updateProjection();
	COccupancyGridMap2D::saveMetricMapRepresentationToFile(prefix);
	m_octomap.saveMetricMapRepresentationToFile(prefix + "_octomap");
}

// ---------------------------------------------------------------------------
// v0 = base grid (with its own version) + octoOptions as (key, value) pairs +
// the COctoMap object.
uint8_t COctoMapGrid2D::serializeGetVersion() const { return 0; }

void COctoMapGrid2D::serializeTo(mrpt::serialization::CArchive& out) const
{
	if (m_dirty) const_cast<COctoMapGrid2D*>(this)->updateProjection();
	out << COccupancyGridMap2D::serializeGetVersion();
	COccupancyGridMap2D::serializeTo(out);
	gam::maps::ini::write(octoOptions, out);
	out << m_octomap;
}

void COctoMapGrid2D::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0: {
			uint8_t baseVer;
			in >> baseVer;
			COccupancyGridMap2D::serializeFrom(in, baseVer);
			gam::maps::ini::read(octoOptions, in, "COctoMapGrid2D");
			in >> m_octomap;
			m_dirty = false;
			m_sinceProjection = 0;
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}
