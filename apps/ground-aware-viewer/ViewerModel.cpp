// Ground-aware mapping for MRPT -- ground-aware-viewer, the GUI-free part.
#include "ViewerModel.h"

#include <gam/maps/GridIO.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/img/CImage.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/maps/TMetricMapTypesRegistry.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/opengl/CFBORender.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/CPointCloud.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/opengl/CTexturedPlane.h>
#include <mrpt/opengl/stock_objects.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "gam/mapper/Mapper.h"
#include "gam/mapper/RawlogFrames.h"

using mrpt::maps::CGroundAwareOccupancyGrid;
using mrpt::maps::CHeightBandOccupancyGrid;
using mrpt::maps::COctoMapGrid2D;

namespace gam::viewer
{
namespace
{
double msSince(std::chrono::steady_clock::time_point t0)
{
	return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

template <class T>
std::shared_ptr<T> create(const mrpt::maps::TMetricMapInitializer& def)
{
	std::shared_ptr<mrpt::maps::CMetricMap> m(
		mrpt::maps::internal::TMetricMapTypesRegistry::Instance().factoryMapObjectFromDefinition(def));
	auto t = std::dynamic_pointer_cast<T>(m);
	if (!t) throw std::runtime_error("internal: map factory returned the wrong class");
	return t;
}
}  // namespace

// ---------------------------------------------------------------------------
// ViewerModel
// ---------------------------------------------------------------------------
ViewerModel::ViewerModel() { loadConfig(""); }

void ViewerModel::loadConfig(const std::string& iniPath, const std::string& section)
{
	std::shared_ptr<mrpt::maps::TMetricMapInitializer> defGA, defHB, defOC, defEL;
	if (!iniPath.empty())
	{
		if (!std::filesystem::exists(iniPath)) throw std::runtime_error("cannot read " + iniPath);
		mrpt::config::CConfigFile ini(iniPath);
		mrpt::maps::TSetOfMetricMapInitializers inits;
		std::vector<gam::mapper::MapSpec> specs;
		gam::mapper::loadMapDefinitions(ini, section, inits, specs);
		for (const auto& d : inits)
		{
			const std::string cls = d->getMetricMapClassType()->className;
			if (!defGA && cls == "mrpt::maps::CGroundAwareOccupancyGrid") defGA = d;
			if (!defHB && cls == "mrpt::maps::CHeightBandOccupancyGrid") defHB = d;
			if (!defOC && cls == "mrpt::maps::COctoMapGrid2D") defOC = d;
			if (!defEL && cls == "mrpt::maps::CElevation25DMap") defEL = d;
		}
	}
	if (!defGA) defGA = std::make_shared<CGroundAwareOccupancyGrid::TMapDefinition>();
	if (!defHB) defHB = std::make_shared<CHeightBandOccupancyGrid::TMapDefinition>();
	if (!defOC) defOC = std::make_shared<COctoMapGrid2D::TMapDefinition>();
	if (!defEL)
	{
		auto d = std::make_shared<mrpt::maps::CElevation25DMap::TMapDefinition>();
		d->min_x = d->min_y = -10;
		d->max_x = d->max_y = 10;
		defEL = d;
	}
	m_elTemplate = create<mrpt::maps::CElevation25DMap>(*defEL);
	m_gaTemplate = create<CGroundAwareOccupancyGrid>(*defGA);
	m_hbTemplate = create<CHeightBandOccupancyGrid>(*defHB);
	m_ocTemplate = create<COctoMapGrid2D>(*defOC);
	m_configPath = iniPath;  // (a later loadInitialMap re-reads it)
	m_configSection = section;
	applyInitialMap();
	const int cur = m_current;
	resetMaps();
	if (cur >= 0) seek(cur);
}

void ViewerModel::applyInitialMap()
{
	if (!m_initialMap) return;
	// The octomap's grid is a projection of its octree, redrawn every frame:
	// it cannot start from a grid.
	m_gaTemplate->loadFromStockGrid(*m_initialMap);
	gam::maps::copyGridCells(*m_initialMap, *m_hbTemplate);
}

void ViewerModel::loadInitialMap(const std::string& path)
{
	// Read first: a bad file throws before anything changes.
	m_initialMap =
		path.empty() ? nullptr : std::make_shared<mrpt::maps::COccupancyGridMap2D>(gam::maps::readStockGrid(path));
	m_initialMapPath = path;
	loadConfig(m_configPath, m_configSection);
}

void ViewerModel::saveGroundAwareAsStockGrid(const std::string& path) const
{
	const mrpt::maps::COccupancyGridMap2D stock = m_ga->asStockGrid();
	const bool yaml = path.size() > 5 && (path.substr(path.size() - 5) == ".yaml");
	if (yaml)
	{
		const std::string pgm = path.substr(0, path.size() - 5) + ".pgm";
		gam::maps::writeRosMap(stock, path, pgm, std::filesystem::path(pgm).filename().string());
	}
	else
		gam::maps::writeSerializedGz(stock, path);
}

void ViewerModel::resetMaps()
{
	m_ga = std::make_shared<CGroundAwareOccupancyGrid>(*m_gaTemplate);
	m_gaBefore = std::make_shared<CGroundAwareOccupancyGrid>(*m_gaTemplate);
	m_hb = std::make_shared<CHeightBandOccupancyGrid>(*m_hbTemplate);
	m_oc = std::make_shared<COctoMapGrid2D>(*m_ocTemplate);
	m_el = std::make_shared<mrpt::maps::CElevation25DMap>(*m_elTemplate);
	m_current = -1;
	m_points.clear();
	m_mapPoints.clear();
	m_timing = {};
}

void ViewerModel::openRawlog(const std::string& path)
{
	gam::mapper::RawlogFrameReader rd(path);
	std::vector<Step> steps;
	Step cur;
	gam::mapper::Frame f;
	while (rd.next(f))
	{
		if (cur.obs.empty()) cur.firstFrame = f.index;
		cur.obs.push_back(f.obs);
		cur.poses.push_back(f.robotPose);
		if (IS_CLASS(*f.obs, mrpt::obs::CObservation3DRangeScan))
		{
			cur.has3D = true;
			cur.index3D = cur.obs.size() - 1;
			steps.push_back(std::move(cur));
			cur = Step{};
		}
	}
	if (!cur.obs.empty())
	{
		// trailing 2D scans: one step each if the log has no 3D scan at all,
		// else they are appended to the last step
		if (steps.empty())
			for (size_t i = 0; i < cur.obs.size(); i++)
			{
				Step s;
				s.firstFrame = cur.firstFrame + i;
				s.obs = {cur.obs[i]};
				s.poses = {cur.poses[i]};
				steps.push_back(std::move(s));
			}
		else
			for (size_t i = 0; i < cur.obs.size(); i++)
			{
				steps.back().obs.push_back(cur.obs[i]);
				steps.back().poses.push_back(cur.poses[i]);
			}
	}
	if (steps.empty()) throw std::runtime_error(path + ": no 3D or 2D range scan with data");
	m_steps = std::move(steps);
	m_rawlog = path;
	resetMaps();
}

void ViewerModel::insertStep(size_t k)
{
	const Step& s = m_steps.at(k);
	*m_gaBefore = *m_ga;
	m_timing = {};
	for (size_t i = 0; i < s.obs.size(); i++)
	{
		auto t0 = std::chrono::steady_clock::now();
		m_ga->insertObservation(*s.obs[i], s.poses[i]);
		m_timing.groundAware += msSince(t0);
		t0 = std::chrono::steady_clock::now();
		m_hb->insertObservation(*s.obs[i], s.poses[i]);
		m_timing.heightBand += msSince(t0);
		t0 = std::chrono::steady_clock::now();
		m_oc->insertObservation(*s.obs[i], s.poses[i]);
		m_timing.octomap += msSince(t0);
		t0 = std::chrono::steady_clock::now();
		m_el->insertObservation(*s.obs[i], s.poses[i]);
		m_timing.elevation += msSince(t0);
	}
	m_current = int(k);
	updatePoints();
	// every 8th point of the frame into the accumulated cloud
	for (size_t i = 0; i < m_points.size(); i += 8) m_mapPoints.push_back(m_points[i]);
}

void ViewerModel::seek(int k)
{
	if (m_steps.empty()) return;
	k = std::clamp(k, -1, int(m_steps.size()) - 1);
	if (k < m_current)
	{
		const auto opts = m_ga->groundOptions();
		resetMaps();
		m_ga->setGroundOptions(opts);
	}
	while (m_current < k) insertStep(size_t(m_current + 1));
}

bool ViewerModel::next()
{
	if (m_current + 1 >= int(m_steps.size())) return false;
	insertStep(size_t(m_current + 1));
	return true;
}

void ViewerModel::rerunCurrent()
{
	if (m_current < 0) return;
	const auto opts = m_ga->groundOptions();
	*m_ga = *m_gaBefore;
	m_ga->setGroundOptions(opts);
	// only the ground-aware grid depends on the options: keep the others
	const Step& s = m_steps.at(size_t(m_current));
	*m_gaBefore = *m_ga;
	m_timing.groundAware = 0;
	for (size_t i = 0; i < s.obs.size(); i++)
	{
		const auto t0 = std::chrono::steady_clock::now();
		m_ga->insertObservation(*s.obs[i], s.poses[i]);
		m_timing.groundAware += msSince(t0);
	}
}

void ViewerModel::applyGroundOptions(const CGroundAwareOccupancyGrid::TGroundAwareOptions& o)
{
	m_ga->setGroundOptions(o);  // validates first: unchanged if it throws
	rerunCurrent();
}

mrpt::poses::CPose3D ViewerModel::currentPose() const
{
	if (m_current < 0) return m_steps.empty() ? mrpt::poses::CPose3D() : m_steps[0].poses[0];
	return m_steps[size_t(m_current)].poses.back();
}

std::vector<mrpt::poses::CPose3D> ViewerModel::pathSoFar() const
{
	std::vector<mrpt::poses::CPose3D> p;
	for (int i = 0; i <= m_current; i++) p.push_back(m_steps[size_t(i)].poses.back());
	return p;
}

void ViewerModel::updatePoints()
{
	m_points.clear();
	if (m_current < 0) return;
	const Step& s = m_steps[size_t(m_current)];
	if (!s.has3D) return;
	const auto& obs = dynamic_cast<const mrpt::obs::CObservation3DRangeScan&>(*s.obs[s.index3D]);
	const auto& pose = s.poses[s.index3D];
	mrpt::obs::T3DPointsProjectionParams pp;
	pp.takeIntoAccountSensorPoseOnRobot = true;
	pp.robotPoseInTheWorld = pose;
	if (obs.hasRangeImage)
	{
		const int W = int(obs.rangeImage.cols()), H = int(obs.rangeImage.rows());
		for (uint8_t d : {4, 2, 1})
			if (W % d == 0 && H % d == 0)
			{
				pp.decimation = d;
				break;
			}
	}
	mrpt::maps::CSimplePointsMap pts;
	auto& o = const_cast<mrpt::obs::CObservation3DRangeScan&>(obs);
	if (obs.hasRangeImage)
		o.unprojectInto(pts, pp);
	else if (obs.hasPoints3D)
		for (size_t i = 0; i < obs.points3D_x.size(); i++)
		{
			const auto p = pose + (obs.sensorPose +
								   mrpt::poses::CPoint3D(obs.points3D_x[i], obs.points3D_y[i], obs.points3D_z[i]));
			pts.insertPoint(p.x(), p.y(), p.z());
		}
	const auto& xs = pts.getPointsBufferRef_x();
	const auto& ys = pts.getPointsBufferRef_y();
	const auto& zs = pts.getPointsBufferRef_z();
	m_points.reserve(xs.size());
	for (size_t i = 0; i < xs.size(); i++) m_points.emplace_back(xs[i], ys[i], zs[i]);
}

std::string ViewerModel::statusText() const
{
	std::ostringstream o;
	o.setf(std::ios::fixed);
	o.precision(2);
	o << "step " << (m_current + 1) << " / " << m_steps.size();
	if (m_current < 0)
	{
		o << " (nothing inserted yet)\n";
		return o.str();
	}
	const Step& s = m_steps[size_t(m_current)];
	const auto p = s.poses.back();
	o << "  frames " << s.firstFrame << ".." << (s.firstFrame + s.obs.size() - 1) << "  robot (" << p.x() << ", "
	  << p.y() << ", " << mrpt::RAD2DEG(p.yaw()) << " deg)\n";
	const auto& d = m_ga->lastFrame();
	if (s.has3D && d.valid)
	{
		o << "ground: " << d.detection.describe() << "\n";
		o << "voxels: ground " << d.ism.ground << ", obstacle " << d.ism.obstacle << ", drop " << d.ism.drop
		  << ", out of range " << d.ism.out_of_range << ", drop-ray cells " << d.ism.drop_ray_cells << "; points "
		  << d.points << "\n";
		if (d.camera != gam::CameraModel::Custom || std::isfinite(d.trust_range))
		{
			o << "camera: " << gam::kCameraModelNames[int(d.camera)];
			if (std::isfinite(d.trust_range))
				o << ", range of trust " << d.trust_range << " m (no evidence farther: its noise hides a "
				  << m_ga->groundOptions().pipeline.ism.traversable_step << " m hazard there)";
			o << "\n";
		}
		o << "stages [ms]: projection " << d.ms.projection << ", outliers " << d.ms.outliers << ", ground "
		  << d.ms.ground << ", ism " << d.ms.ism << ", update " << m_ga->lastFrameTimes().update << ", total "
		  << m_ga->lastFrameTimes().total << "\n";
	}
	else
		o << "(no 3D scan in this step)\n";
	for (const auto& [label, monitor] : m_ga->mountChecks())
	{
		const MountStatus& ms = monitor.status();
		if (!ms.has_last) continue;
		if (ms.alarm) o << "WARNING: MOUNT ALARM, " << label << "'s declared sensorPose disagrees with the floor\n";
		o << "mount " << label << ": measured z " << std::setprecision(3) << ms.estimate.height << " m, pitch "
		  << std::setprecision(2) << mrpt::RAD2DEG(ms.estimate.pitch) << ", roll " << mrpt::RAD2DEG(ms.estimate.roll)
		  << " deg; declared z " << std::setprecision(3) << ms.declared.height << ", pitch " << std::setprecision(2)
		  << mrpt::RAD2DEG(ms.declared.pitch) << ", roll " << mrpt::RAD2DEG(ms.declared.roll) << "; "
		  << ms.frames_disagreeing << " of " << ms.frames_checked << " frames disagree\n";
	}
	o << "insert [ms]: ground_aware " << m_timing.groundAware << ", height_band " << m_timing.heightBand << ", octomap "
	  << m_timing.octomap << ", elevation " << m_timing.elevation << "\n";
	return o.str();
}

}  // namespace gam::viewer
