#include <gam/maps/GridIO.h>
#include <gam/maps/IniFields.h>
#include <gam/maps/MapRegistry.h>
#include <gam/maps/ObservationAdapters.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/core/format.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>

using namespace mrpt::maps;

MAP_DEFINITION_REGISTER("mrpt::maps::CGroundAwareOccupancyGrid,groundAwareGrid", mrpt::maps::CGroundAwareOccupancyGrid)
IMPLEMENTS_SERIALIZABLE(CGroundAwareOccupancyGrid, COccupancyGridMap2D, mrpt::maps)

namespace
{
// 2D scans without a depth frame before the "no free space" warning: a walker
// whose Leddar starts before its camera stays below it.
constexpr uint64_t kScansBeforeWarning = 10;

// What tools need to know about this class (gam/maps/MapRegistry.h).
const bool kTraitsRegistered = [] {
	gam::maps::MapTraits t;
	t.className = "mrpt::maps::CGroundAwareOccupancyGrid";
	t.sections = {
		{"_creationOpts", gam::maps::gridCreationKeys()},
		{"_insertOpts", {}},
		{"_likelihoodOpts", {}},
		{"_groundOpts", gam::maps::ini::keys<CGroundAwareOccupancyGrid::TGroundAwareOptions>()}};
	t.writeOutputs = [](CMetricMap& m, const gam::maps::OutputContext& ctx, std::vector<std::string>& files) {
		gam::maps::writeGridOutputs(m, ctx, files);
		// The missing-floor layer as its own map_server pair and PNG (after
		// writeGridOutputs, which crops a local map: the layer follows).
		const auto& g = dynamic_cast<const CGroundAwareOccupancyGrid&>(m);
		COccupancyGridMap2D layer = g.missingFloorLayer();
		const std::string stem = ctx.label + "_missing_floor", base = ctx.dir + "/" + stem;
		gam::maps::writeRosMap(layer, base + ".yaml", base + ".pgm", stem + ".pgm");
		gam::maps::PngStyle style;
		style.legend = ctx.pngLegend;
		gam::maps::writeGridPng(layer, base + ".png", style);
		if (ctx.pngLegend)
		{
			// The map's picture again, with its missing floor in orange.
			style.missing = &layer;
			gam::maps::writeGridPng(g, ctx.dir + "/" + ctx.label + ".png", style);
		}
		for (const char* ext : {".yaml", ".pgm", ".png"}) files.push_back(stem + ext);
	};
	// The missing-floor layer follows the grid's window: missingFloorLayer() re-syncs it.
	t.keepWindow = gam::maps::keepGridWindow;
	t.startFromGrid = [](CMetricMap& m, const COccupancyGridMap2D& stock) {
		dynamic_cast<CGroundAwareOccupancyGrid&>(m).loadFromStockGrid(stock);
	};
	t.stageTimes = [](const CMetricMap& m, bool depthFrame, const gam::maps::StageSink& sink) {
		const auto& g = dynamic_cast<const CGroundAwareOccupancyGrid&>(m);
		if (!depthFrame || !g.lastFrame().valid) return;
		const gam::StageTimes& ms = g.lastFrame().ms;
		sink("projection", ms.projection);
		sink("outliers", ms.outliers);
		sink("ground", ms.ground);
		sink("ism", ms.ism);
		sink("missing_floor", ms.missing);
		sink("update", g.lastFrameTimes().update);
	};
	t.lastGroundPlane = [](const CMetricMap& m, gam::maps::GroundPlaneRecord& r) {
		const auto& g = dynamic_cast<const CGroundAwareOccupancyGrid&>(m);
		if (!g.lastFrame().valid) return false;
		const gam::GroundDetection& det = g.lastFrame().detection;
		r = gam::maps::GroundPlaneRecord{};
		if (det.ok() && !det.planes.empty())
		{
			const gam::Plane& p = det.plane();
			r.found = true;
			r.a = p.a, r.b = p.b, r.c = p.c, r.d = p.d;
		}
		r.nodes = det.nodes.size();
		for (size_t k = 1; det.ok() && k < det.planes.size(); k++)
		{
			const gam::Plane& p = det.planes[k];
			r.patches.push_back({p.a, p.b, p.c, p.d, k < det.plane_support.size() ? det.plane_support[k] : 0, false});
		}
		const gam::FrameResult& fr = g.lastFrame();
		for (size_t k = 0; k < fr.remembered_planes.size(); k++)
		{
			const gam::Plane& p = fr.remembered_planes[k];
			r.patches.push_back({p.a, p.b, p.c, p.d, fr.remembered_support[k], true});
		}
		// "mount_floor": the tree's plane was too far from the robot's floor,
		// the frame was judged against that floor (max_ground_offset).
		r.status = det.ok() && det.ground_from_mount ? "mount_floor" : gam::GroundDetection::statusName(det.status);
		const auto it = g.mountChecks().find(g.lastSensorLabel());
		if (it != g.mountChecks().end() && it->second.status().has_last && r.found)
		{
			const gam::MountStatus& ms = it->second.status();
			r.mount_measured = true;
			r.mount_z = ms.last.height;
			r.mount_pitch_deg = ms.last.pitch * 180.0 / M_PI;
			r.mount_roll_deg = ms.last.roll * 180.0 / M_PI;
			r.mount_alarm = ms.alarm;
		}
		return true;
	};
	t.runNote = [](const CMetricMap& m) {
		const auto& g = dynamic_cast<const CGroundAwareOccupancyGrid&>(m);
		std::string out;
		for (const auto& [label, monitor] : g.mountChecks())
		{
			const gam::MountStatus& s = monitor.status();
			if (!s.frames_checked) continue;
			const double k = 180.0 / M_PI;
			char b[512];
			std::snprintf(
				b, sizeof b,
				"sensor mount %s: declared z=%.3f m pitch=%.2f roll=%.2f deg, measured (median of the last %d frames) "
				"z=%.3f pitch=%.2f roll=%.2f; %zu of %zu frames disagree (tolerance %.3f m, %.2f deg)%s",
				label.c_str(), s.declared.height, s.declared.pitch * k, s.declared.roll * k,
				g.groundOptions().mount.window, s.estimate.height, s.estimate.pitch * k, s.estimate.roll * k,
				s.frames_disagreeing, s.frames_checked, g.groundOptions().mount.tolerance_z,
				g.groundOptions().mount.tolerance_deg,
				s.alarm
					? ": MOUNT ALARM, the declared sensorPose is wrong or the camera moved (gam-calibrate measures it)"
					: (s.alarms_raised ? ": the alarm was raised and cleared again" : ""));
			out += (out.empty() ? "" : "\n") + std::string(b);
		}
		if (g.groundOptions().threads > 1)
		{
			const auto& ps = g.parallelStats();
			out += (out.empty() ? "" : "\n") +
				   mrpt::format(
					   "threads=%d: %llu depth frames fused from a pipeline that ran alongside another camera's (%llu "
					   "of them "
					   "on a worker thread), %llu run again in their turn (the grid had moved under them)",
					   g.groundOptions().threads, (unsigned long long)ps.ran_ahead, (unsigned long long)ps.on_worker,
					   (unsigned long long)ps.run_again);
		}
		const gam::PipelineParams& pp = g.groundOptions().pipeline;
		for (const auto& [label, cam] : g.cameras())
		{
			if (pp.ism.model == gam::MethodVariant::Paper) break;  // the paper's model has no camera noise
			char b[512];
			const char* name = gam::kCameraModelNames[int(cam.model)];
			const bool unknown = cam.model == gam::CameraModel::Custom && pp.camera.model == gam::CameraModel::Auto;
			const std::string trust =
				!pp.camera.range_of_trust
					? std::string("range_of_trust off")
					: (std::isfinite(cam.trust_range) && cam.trust_range < pp.projection.max_range
						   ? "range of trust " + mrpt::format("%.2f m", cam.trust_range)
						   : "range of trust: the whole max_range " + mrpt::format("%.2f m", pp.projection.max_range));
			std::snprintf(
				b, sizeof b, "camera %s: %s%s (%dx%d, %.2f m above the floor), %s for a %.3f m hazard at %.1f sigma",
				label.c_str(), unknown ? "unknown" : name,
				unknown ? " (camera_model = auto found no model for this frame size and label: no noise model; set "
						  "camera_model)"
						: (pp.camera.model == gam::CameraModel::Auto ? " (auto)" : ""),
				cam.width, cam.height_px, cam.height, trust.c_str(), pp.ism.traversable_step, pp.ism.noise_sigmas);
			out += (out.empty() ? "" : "\n") + std::string(b);
			if (cam.dead_border_columns > 0)
				out += mrpt::format(
					"; %d image columns at its borders returned nothing in any row of its last frame (the band of a "
					"depth image registered to colour, or of a stereo camera): no floor evidence there",
					cam.dead_border_columns);
		}
		return out;
	};
	gam::maps::registerMapTraits(std::move(t));
	return true;
}();
}  // namespace

// The stock options keep the stock defaults (considerInvalidRangesAsFreeSpace
// = true among them), so that an .ini written for COccupancyGridMap2D means
// the same here; the walker's .ini files set what a Leddar needs (a "no
// return" is not free space). Only the resolution differs: 0.05 m, the
// paper's d_r, against the stock .ini default of 0.10 m.
CGroundAwareOccupancyGrid::TMapDefinition::TMapDefinition() = default;

void CGroundAwareOccupancyGrid::TMapDefinition::loadFromConfigFile_map_specific(
	const mrpt::config::CConfigFileBase& source, const std::string& sectionNamePrefix)
{
	const std::string sC = sectionNamePrefix + "_creationOpts";
	gam::maps::ini::loadGridExtent(source, sC, min_x, max_x, min_y, max_y, resolution);
	insertionOpts.loadFromConfigFile(source, sectionNamePrefix + "_insertOpts");
	likelihoodOpts.loadFromConfigFile(source, sectionNamePrefix + "_likelihoodOpts");
	groundOpts.loadFromConfigFile(source, sectionNamePrefix + "_groundOpts");
}

void CGroundAwareOccupancyGrid::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const
{
	out << "min_x=" << min_x << " max_x=" << max_x << " min_y=" << min_y << " max_y=" << max_y
		<< " resolution=" << resolution << "\n";
	insertionOpts.dumpToTextStream(out);
	likelihoodOpts.dumpToTextStream(out);
	groundOpts.dumpToTextStream(out);
}

mrpt::maps::CMetricMap* CGroundAwareOccupancyGrid::internal_CreateFromMapDefinition(const TMetricMapInitializer& _def)
{
	const auto& def = dynamic_cast<const CGroundAwareOccupancyGrid::TMapDefinition&>(_def);
	auto* m = new CGroundAwareOccupancyGrid(def.min_x, def.max_x, def.min_y, def.max_y, def.resolution);
	m->insertionOptions = def.insertionOpts;
	m->likelihoodOptions = def.likelihoodOpts;
	m->setGroundOptions(def.groundOpts);
	return m;
}

// ---------------------------------------------------------------------------
void CGroundAwareOccupancyGrid::TGroundAwareOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& source, const std::string& section)
{
	gam::maps::ini::loadThenCheck(*this, source, section, [this] { validate(); });
}

void CGroundAwareOccupancyGrid::TGroundAwareOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& target, const std::string& section) const
{
	gam::maps::ini::save(*this, target, section);
}

void CGroundAwareOccupancyGrid::TGroundAwareOptions::validate() const
{
	gam::checkParamRanges(*this, "");
	pipeline.validate();
}

void CGroundAwareOccupancyGrid::setGroundOptions(const TGroundAwareOptions& o)
{
	o.validate();
	m_idlePipeline.setParams(o.pipeline);
	for (auto& [label, pipeline] : m_pipelines) pipeline.setParams(o.pipeline);
	for (auto& [label, monitor] : m_mounts) monitor.setParams(o.mount);
	// A pipeline that ran ahead ran with the old parameters.
	for (TBatchSlot& slot : m_batch) slot.ran = false;
	m_pool.resize(o.threads);
	m_options = o;
}

bool CGroundAwareOccupancyGrid::mountAlarm() const
{
	for (const auto& [label, monitor] : m_mounts)
		if (monitor.status().alarm) return true;
	return false;
}

// ---------------------------------------------------------------------------
CGroundAwareOccupancyGrid::CGroundAwareOccupancyGrid(
	float min_x, float max_x, float min_y, float max_y, float resolution)
	: COccupancyGridMap2D(min_x, max_x, min_y, max_y, resolution)
{
	// The stock insertion and likelihood defaults (see TMapDefinition).
}

void CGroundAwareOccupancyGrid::resetRunState()
{
	m_missingLayer.setSize(getXMin(), getXMax(), getYMin(), getYMax(), getResolution(), 0.5f);
	m_scanOnlyLayer.setSize(getXMin(), getXMax(), getYMin(), getYMax(), getResolution(), 0.5f);
	m_positiveSeen.clear();
	// A new map: no ramp patch of the last run's frames judges the next ones.
	for (auto& [label, pipeline] : m_pipelines) pipeline.forgetPatches();
	m_depthFrames = 0;
	m_scansBeforeDepth = 0;
	m_warnedNoFreeSpace = false;
}

void CGroundAwareOccupancyGrid::internal_clear()
{
	COccupancyGridMap2D::internal_clear();
	resetRunState();
}

bool CGroundAwareOccupancyGrid::scanRuleActive() const
{
	using R = TGroundAwareOptions::ScanRule;
	switch (m_options.scan_keeps_3d_obstacles)
	{
		case R::KeepCameraFloor: return true;
		case R::Auto: return m_depthFrames > 0;
		default: return false;
	}
}

void CGroundAwareOccupancyGrid::loadFromStockGrid(const COccupancyGridMap2D& stock)
{
	gam::maps::copyGridCells(stock, *this);
	// (A deserialized stock grid reports isEmpty() whatever its cells hold:
	// the flag is not serialized. A cell that is not unknown decides.)
	m_is_empty = stock.isEmpty() && std::all_of(m_map.begin(), m_map.end(), [](cellType c) { return c == 0; });
	m_likelihoodCacheOutDated = true;
	resetRunState();
}

COccupancyGridMap2D CGroundAwareOccupancyGrid::asStockGrid() const { return COccupancyGridMap2D(*this); }

std::string CGroundAwareOccupancyGrid::asString() const
{
	std::ostringstream s;
	s << "CGroundAwareOccupancyGrid " << getSizeX() << "x" << getSizeY() << " cells at " << getResolution() << " m, x["
	  << getXMin() << "," << getXMax() << "] y[" << getYMin() << "," << getYMax() << "]";
	return s.str();
}

mrpt::obs::CObservation2DRangeScan CGroundAwareOccupancyGrid::upsampleSparseScan(
	const mrpt::obs::CObservation2DRangeScan& in, int k, bool nearEdge)
{
	const size_t N = in.getScanSize();
	if (k <= 1 || N == 0 || N >= 64) return in;
	mrpt::obs::CObservation2DRangeScan out = in;
	// Beam i points at -aperture/2 + i s (s = aperture / (N - 1)) and covers
	// s around it: its k rays sit at the centres of k equal parts of that
	// cone, s / k apart. So the new aperture spans N k - 1 of those steps. (It
	// kept the old aperture, which squeezed the rays inward: an edge segment
	// lost the outer half of its cone, and a segment's echo was drawn up to
	// 1.1 deg (k = 8) inside its neighbour's cone, behind the wall the
	// neighbour saw nearer when it met a wall at a grazing angle.)
	const double s = N > 1 ? double(in.aperture) / double(N - 1) : double(in.aperture);
	if (N > 1) out.aperture = float(s * double(N * size_t(k) - 1) / double(k));
	out.resizeScan(N * size_t(k));
	// Angles in beam-index order (mirroring the scan for rightToLeft = false
	// changes no range below).
	const auto centre = [&](size_t i) { return -0.5 * double(in.aperture) + double(i) * s; };
	const auto valid = [&](size_t i) { return in.getScanRangeValidity(i) && in.getScanRange(i) > 0; };
	const auto range = [&](size_t i) { return double(in.getScanRange(i)); };
	// A beam's own cone: its beamAperture where the scan gives one (the
	// simulated Leddar's 2.8125 deg segments sit 3 deg apart), else the spacing.
	const double cone = in.beamAperture > 0 && double(in.beamAperture) < s ? double(in.beamAperture) : s;
	// How far from a line three echoes of one flat surface may lie: 3 sigma of
	// the scan's range noise (the Leddar IS16's 2.5 cm when the scan does
	// not say).
	const double straight = 3.0 * (in.stdError > 0 ? double(in.stdError) : 0.025);
	for (size_t i = 0; i < N; i++)
	{
		const double r = range(i);
		// A beam's echo is the nearest return in its cone. Where the ranges
		// recede from beam to beam (a surface seen obliquely), that return is
		// at the cone's edge toward the nearer neighbour, and so is the
		// neighbour's own echo at its edge: two points of the surface that
		// bracket the cone. The rays end on the chord between them, never
		// nearer than the echo. Drawn as an arc at the echo's range instead,
		// the cone's far side lands in front of the surface: 12.4 cm (two
		// cells) for the outer beam of a 16-beam, 45 deg Leddar (its cone 21 to
		// 24 deg) facing a wall 5.8 m away, 5.8 (1 - cos 24 / cos 21).
		// Elsewhere (a nearest point inside the cone: a pole, the foot of the
		// perpendicular; no neighbour echo; a jump that no surface at more
		// than kMinIncidence from the rays makes): the arc.
		// A concave corner: where this segment's surface, extended (the line
		// through the nearer neighbour's echo and this one's, both at their
		// near edges), passes behind the farther neighbour's echo, a second
		// surface meets it inside the cones, and the chord would cut the
		// corner. There the rays end on that line but no farther than the
		// neighbour's echo: the nearer of the two surfaces, as seen from
		// inside a corner. (Two earlier checks for such corners kept the arc
		// instead and marked more floor on the 27 scenes, D435 1176 -> 1215
		// and -> 1191 cells: see doc/benchmark.md.)
		double ax = 0, ay = 0, bx = 0, by = 0, cap = 0;
		bool chord = false;
		if (nearEdge && valid(i) && N > 1)
		{
			const bool prevNearer = i > 0 && valid(i - 1) && range(i - 1) < r;
			const bool prevFarther = i > 0 && valid(i - 1) && range(i - 1) > r;
			const bool nextNearer = i + 1 < N && valid(i + 1) && range(i + 1) < r;
			const bool nextFarther = i + 1 < N && valid(i + 1) && range(i + 1) > r;
			const auto at = [&](size_t seg, double edge, double& x, double& y) {
				const double a = centre(seg) + edge;
				x = range(seg) * std::cos(a);
				y = range(seg) * std::sin(a);
			};
			// The concave-corner test for a segment receding from `nearer` (itself
			// receding from `nearer2`, so its echo is at its near edge too)
			// toward `farther`; `edge` is the near edges' side.
			const auto corner = [&](size_t nearer, size_t nearer2, size_t farther, double edge) {
				if (!valid(nearer) || !valid(nearer2) || !(range(nearer2) < range(nearer))) return;
				double px = 0, py = 0, qx = 0, qy = 0;
				at(nearer, edge, px, py);
				at(nearer2, edge, qx, qy);
				const double lx = px - ax, ly = py - ay, ll = std::hypot(lx, ly);
				// One straight surface over three cones: the third echo within
				// 3 sigma of the scan's range noise of the line (else the line
				// may run behind what this cone saw).
				if (!(ll > 0) || std::abs(lx * (qy - ay) - ly * (qx - ax)) / ll > straight) return;
				// This surface extended, at the farther neighbour's echo direction.
				const double a = centre(farther) + edge;
				const double den = std::cos(a) * ly - std::sin(a) * lx;
				if (!(std::abs(den) > 0)) return;
				const double t = (ax * ly - ay * lx) / den;
				if (t > range(farther))
				{
					bx = px;
					by = py;
					cap = range(farther);
				}
			};
			if (!prevFarther && !nextNearer && (i == 0 || valid(i - 1)) && (nextFarther || prevNearer))
			{
				// Receding toward i + 1: each echo is at its cone's edge toward
				// i - 1. The other point: i + 1's, or past the scan's end (or
				// i + 1's missing echo) i - 1's.
				at(i, -0.5 * cone, ax, ay);
				at(nextFarther ? i + 1 : i - 1, -0.5 * cone, bx, by);
				chord = true;
				if (nextFarther && prevNearer && i >= 2) corner(i - 1, i - 2, i + 1, -0.5 * cone);
			}
			else if (!nextFarther && !prevNearer && (i + 1 == N || valid(i + 1)) && (prevFarther || nextNearer))
			{
				at(i, 0.5 * cone, ax, ay);
				at(prevFarther ? i - 1 : i + 1, 0.5 * cone, bx, by);
				chord = true;
				if (prevFarther && nextNearer && i + 2 < N) corner(i + 1, i + 2, i - 1, 0.5 * cone);
			}
		}
		// The ray (cos a, sin a) t meets A + (B - A) u where
		// t = cross(A, B - A) / cross(ray, B - A).
		const double dx = bx - ax, dy = by - ay, len = std::hypot(dx, dy), cross = ax * dy - ay * dx;
		for (int j = 0; j < k; j++)
		{
			const size_t o = i * size_t(k) + size_t(j);
			double ro = r;
			if (chord)
			{
				const double a = centre(i) - 0.5 * s + (j + 0.5) * s / k;
				const double den = std::cos(a) * dy - std::sin(a) * dx;
				if (cap > 0)
				{
					// Parallel to the ray, or met behind the sensor: the cap alone.
					const double t = std::abs(den) > 0 ? cross / den : 0;
					ro = std::max(r, t > 0 ? std::min(t, cap) : cap);
				}
				else if (len > 0 && std::abs(den) >= len * std::sin(kMinIncidence))
					ro = std::max(r, cross / den);
			}
			out.setScanRange(o, float(ro));
			out.setScanRangeValidity(o, in.getScanRangeValidity(i));
		}
	}
	return out;
}

bool CGroundAwareOccupancyGrid::internal_insertObservation(
	const mrpt::obs::CObservation& obs, const std::optional<const mrpt::poses::CPose3D>& robotPose)
{
	using namespace mrpt::obs;
	const mrpt::poses::CPose3D pose = robotPose ? *robotPose : mrpt::poses::CPose3D();
	if (const auto* o2 = dynamic_cast<const CObservation2DRangeScan*>(&obs)) return insert2D(*o2, robotPose);
	if (IS_CLASS(obs, CObservation3DRangeScan) || IS_CLASS(obs, CObservationPointCloud)) return insert3D(obs, pose);
	return COccupancyGridMap2D::internal_insertObservation(obs, robotPose);
}

namespace
{
// The world box that holds every cell MRPT 2.5's beam model can change for
// scan `s` from `laser` (COccupancyGridMap2D_insert.cpp): rays from the sensor
// at angles phi -+ aperture / 2 in steps of aperture / N, each ending at
// min(maxDistanceInsertion, range), an invalid range as free space (if so
// set) at half the last valid one, and a widened beam half a step either
// side of its ray. So: the sensor and the arc at the farthest such end over
// that span and a step more each side, one cell more all round.
struct WorldBox
{
	double x0, y0, x1, y1;
};
WorldBox scanReach(
	const mrpt::obs::CObservation2DRangeScan& s, const mrpt::poses::CPose2D& laser,
	const COccupancyGridMap2D::TInsertionOptions& o, double res)
{
	double reach = 0, lastValid = o.maxDistanceInsertion;
	for (size_t i = 0; i < s.getScanSize(); i++)
		if (s.getScanRangeValidity(i))
		{
			lastValid = s.getScanRange(i);
			reach = std::max(reach, std::min(double(o.maxDistanceInsertion), lastValid));
		}
		else if (o.considerInvalidRangesAsFreeSpace)
			reach = std::max(reach, std::min(double(o.maxDistanceInsertion), 0.5 * lastValid));
	const double px = laser.x(), py = laser.y();
	WorldBox b{px, py, px, py};
	const auto take = [&](double a) {
		b.x0 = std::min(b.x0, px + reach * std::cos(a));
		b.x1 = std::max(b.x1, px + reach * std::cos(a));
		b.y0 = std::min(b.y0, py + reach * std::sin(a));
		b.y1 = std::max(b.y1, py + reach * std::sin(a));
	};
	const double step = s.getScanSize() > 0 ? std::abs(double(s.aperture)) / double(s.getScanSize()) : 0.0;
	const double half = 0.5 * std::abs(double(s.aperture)) + step;
	if (half >= M_PI)
		take(0), take(M_PI_2), take(M_PI), take(-M_PI_2);
	else
	{
		const double a0 = laser.phi() - half, a1 = laser.phi() + half;
		take(a0);
		take(a1);
		// The arc's extremes: the axis directions it passes.
		for (double k = std::ceil(a0 / M_PI_2); k * M_PI_2 <= a1; k++) take(k * M_PI_2);
	}
	b.x0 -= res;
	b.y0 -= res;
	b.x1 += res;
	b.y1 += res;
	return b;
}
}  // namespace

bool CGroundAwareOccupancyGrid::insert2D(
	const mrpt::obs::CObservation2DRangeScan& rawScan, const std::optional<const mrpt::poses::CPose3D>& robotPose)
{
	const auto scan = gam::maps::safeScanFor(*this, rawScan, robotPose ? *robotPose : mrpt::poses::CPose3D());
	const bool sparse = int(scan.getScanSize()) < 64 && m_options.sparse_scan_upsampling > 1;
	const auto up = sparse ? upsampleSparseScan(scan, m_options.sparse_scan_upsampling, m_options.sparse_scan_near_edge)
						   : mrpt::obs::CObservation2DRangeScan();
	const auto& use = sparse ? up : scan;
	if (m_depthFrames == 0 && ++m_scansBeforeDepth >= kScansBeforeWarning && !m_warnedNoFreeSpace && scanRuleActive())
	{
		// A lidar-only grid with the walker's rule would never get a free cell
		// (MRPT's localization then aborts on "nFreeCells"): say so, once.
		m_warnedNoFreeSpace = true;
		std::cerr << "[CGroundAwareOccupancyGrid] warning: " << m_scansBeforeDepth
				  << " 2D scans and no depth frame: with scan_keeps_3d_obstacles=true 2D scans free no cell, so "
					 "this grid has no free space; for a lidar-only grid set scan_keeps_3d_obstacles=auto (the "
					 "default) or false\n";
	}
	if (!scanRuleActive()) return COccupancyGridMap2D::internal_insertObservation(use, robotPose);

	// A planar beam sees only its own height: passing over a hole, a cable or
	// a 5 cm box says nothing about the floor. So the beam model adds its hits
	// but makes no cell freer: only floor the depth camera saw is free. (It
	// used to reinforce cells already free; at 10 Hz with upsampled rays that
	// drove cells seen as floor from afar -- where a pit's visible part is
	// shallower than the ground band -- to the log-odds clamp, and the drop
	// seen later from close by could no longer mark them: issue #17.)
	// One exception: what scans marked, scans may take back. Each cell keeps
	// the scans' own evidence there, their ledger S (m_scanOnlyLayer): the sum
	// of what MRPT's beam model added, hits (< 0) and rays passing (> 0). The
	// cell holds what the camera (or a loaded map) said, its base, plus the
	// scans' net hits: base + min(0, S), never freer than the base. A wide
	// beam's echo is the nearest return in its cone and is drawn across the
	// whole cone, up to 10 cm in front of a wall seen at an angle from 5 m;
	// the beams that later pass through those cells undo that. And an echo
	// in a cell that scans have seen through since its last echo is taken
	// for the range noise of the surface behind it and adds nothing (a
	// Leddar's 2.5 cm puts 2 % of a far wall's echoes 5 cm or more short, and
	// with a D400 nothing else judges the floor there): a new obstacle in such
	// a cell is marked by its second echo. (It used to keep only a mark
	// "scans made it occupied" and take such a cell back up to unknown: the
	// passes beyond that were lost, and the next short echo marked it again.)
	// Only the cells the scan can reach are compared, before and after. (The
	// whole grid was copied and compared for every scan: 0.20 ms per Leddar
	// scan on a 520 x 400-cell grid, 3.1 ms on 2000 x 2000; now 0.06 ms on
	// both.)
	const double res = getResolution();
	const WorldBox box = scanReach(
		use, mrpt::poses::CPose2D((robotPose ? *robotPose : mrpt::poses::CPose3D()) + use.sensorPose), insertionOptions,
		res);
	const auto cellRange = [&](double lo, double hi, double origin, int size, int& i0, int& i1) {
		i0 = std::clamp(int(std::floor((lo - origin) / res)) - 1, 0, size);
		i1 = std::clamp(int(std::floor((hi - origin) / res)) + 2, 0, size);  // one past the last
	};
	const float x0 = getXMin(), y0 = getYMin();
	const int sx0 = int(getSizeX()), sy0 = int(getSizeY());
	int bx0, bx1, by0, by1;  // the box in the grid before the scan
	cellRange(box.x0, box.x1, x0, sx0, bx0, bx1);
	cellRange(box.y0, box.y1, y0, sy0, by0, by1);
	const int bw = bx1 - bx0;
	m_scanBefore.resize(size_t(std::max(0, bw)) * size_t(std::max(0, by1 - by0)));
	for (int y = by0; y < by1; y++)
		std::copy_n(
			m_map.data() + size_t(y) * size_t(sx0) + size_t(bx0), bw,
			m_scanBefore.data() + size_t(y - by0) * size_t(bw));
	const double scanTime = rawScan.timestamp == INVALID_TIMESTAMP ? 0.0 : mrpt::Clock::toDouble(rawScan.timestamp);
	const bool changed = COccupancyGridMap2D::internal_insertObservation(use, robotPose);
	const int sx = int(getSizeX()), sy = int(getSizeY());
	// The grid may have grown (cell alignment is kept): shift the old indices.
	const int ox = int(std::lround((x0 - getXMin()) / res));
	const int oy = int(std::lround((y0 - getYMin()) / res));
	int nx0, nx1, ny0, ny1;  // the box in the grid now
	cellRange(box.x0, box.x1, getXMin(), sx, nx0, nx1);
	cellRange(box.y0, box.y1, getYMin(), sy, ny0, ny1);
	syncLayer(m_scanOnlyLayer);
	cellType* ledger = m_scanOnlyLayer.getRow(0);
	// Every cell of the box as it is now: a cell the scan grew the grid by was
	// unknown before it (a scan that grew the grid used to free those cells).
	for (int ny = ny0; ny < ny1; ny++)
		for (int nx = nx0; nx < nx1; nx++)
		{
			const int cx = nx - ox, cy = ny - oy;
			const bool wasThere = cx >= 0 && cy >= 0 && cx < sx0 && cy < sy0;
			// (Both ranges are the same world box with a cell to spare, so the
			// copy holds every cell the scan changed; a rim cell that the
			// round-off between the two grids' origins leaves outside the copy
			// was not reached, and its value now is its value before.)
			const cellType old = !wasThere ? cellType(0)
								 : (cx >= bx0 && cx < bx1 && cy >= by0 && cy < by1)
									 ? m_scanBefore[size_t(cy - by0) * size_t(bw) + size_t(cx - bx0)]
									 : m_map[size_t(ny) * size_t(sx) + size_t(nx)];
			const size_t i = size_t(ny) * size_t(sx) + size_t(nx);
			cellType& now = m_map[i];
			if (now == old) continue;
			// A ledger > 0 (1) says "seen through since its last echo".
			const int s0 = ledger[i], d = int(now) - int(old);
			const int s1 = d < 0 && s0 > 0 ? 0 : std::clamp(s0 + d, int(OCCGRID_CELLTYPE_MIN), 1);
			ledger[i] = cellType(s1);
			now = cellType(std::clamp(
				int(old) - std::min(0, s0) + std::min(0, s1), int(OCCGRID_CELLTYPE_MIN), int(OCCGRID_CELLTYPE_MAX)));
			if (m_options.obstacle_decay_s > 0 && now < old) notePositive(nx, ny, scanTime);
		}
	if (m_options.obstacle_decay_s > 0 && scanTime > 0) decayObstacles(scanTime);
	return changed;
}

gam::GroundAwarePipeline& CGroundAwareOccupancyGrid::pipelineFor(const std::string& label)
{
	auto it = m_pipelines.find(label);
	if (it == m_pipelines.end()) it = m_pipelines.emplace(label, gam::GroundAwarePipeline(m_options.pipeline)).first;
	return it->second;
}

const gam::PatchMemory* CGroundAwareOccupancyGrid::rememberedPatches(const std::string& label) const
{
	const auto it = m_pipelines.find(label);
	return it == m_pipelines.end() ? nullptr : &it->second.patchMemory();
}

const gam::GroundAwarePipeline& CGroundAwareOccupancyGrid::lastPipeline() const
{
	if (!m_lastHasPipeline) return m_idlePipeline;
	const auto it = m_pipelines.find(m_lastSensorLabel);
	return it == m_pipelines.end() ? m_idlePipeline : it->second;
}

void CGroundAwareOccupancyGrid::prepareFrame(
	const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose, TPreparedFrame& p)
{
	// Adapt the observation once (samples and sensor pose) onto a frame grid
	// aligned with this grid's cells.
	p.frame = gam::SensorFrame{};
	gam::maps::toSensorFrame(obs, robotPose, p.frame);
	p.pipeline = &pipelineFor(obs.sensorLabel);
	obs.getSensorPose(p.declared);
	p.used = p.declared;
	const auto mon = m_mounts.find(obs.sensorLabel);
	if (mon != m_mounts.end() && m_options.mount.enabled && m_options.mount.use_measured &&
		mon->second.status().has_estimate)
	{
		// x, y and yaw are not observable from the floor: they stay declared.
		const gam::MountStatus& ms = mon->second.status();
		p.used = mrpt::poses::CPose3D(
			p.declared.x(), p.declared.y(), ms.estimate.height, p.declared.yaw(), ms.estimate.pitch, ms.estimate.roll);
		gam::maps::placeSensor(robotPose + p.used, p.frame);
	}
	p.robot = Eigen::Vector3d(robotPose.x(), robotPose.y(), robotPose.z());
	p.lattice = gam::GridLattice{getXMin(), getYMin(), getResolution()};
	p.origin = p.pipeline->gridOrigin(p.robot, p.lattice);
}

bool CGroundAwareOccupancyGrid::TPreparedFrame::sameInputs(const TPreparedFrame& o) const
{
	// Exact comparisons: a result is taken only when its inputs are the same bits.
	const auto pose6 = [](const mrpt::poses::CPose3D& q) {
		return std::array<double, 6>{q.x(), q.y(), q.z(), q.yaw(), q.pitch(), q.roll()};
	};
	return pipeline == o.pipeline && robot == o.robot && origin == o.origin &&
		   lattice.resolution == o.lattice.resolution && pose6(used) == pose6(o.used);
}

bool CGroundAwareOccupancyGrid::insert3D(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose)
{
	using clk = std::chrono::steady_clock;
	const auto t0 = clk::now();
	// Until this frame's pipeline is known, lastFrame() is "no frame".
	m_lastHasPipeline = false;
	m_times = TFrameTimes{};
	m_depthFrames++;

	TPreparedFrame prep;
	prepareFrame(obs, robotPose, prep);
	// The mount check of this sensor (one per label: several cameras).
	if (m_lastSensorLabel != obs.sensorLabel) m_lastSensorLabel = obs.sensorLabel;
	m_lastHasPipeline = true;
	auto mon = m_mounts.find(obs.sensorLabel);
	if (mon == m_mounts.end()) mon = m_mounts.emplace(obs.sensorLabel, gam::MountMonitor(m_options.mount)).first;
	const mrpt::poses::CPose3D& declared = prep.declared;
	const mrpt::poses::CPose3D& used = prep.used;
	gam::GroundAwarePipeline& pipeline = *prep.pipeline;
	const gam::SensorFrame& frame = prep.frame;

	// insertObservations(): this frame's pipeline may have run ahead, on what
	// it would run on now (or not: then it runs again, here).
	double aheadMs = 0;
	TBatchSlot* ahead = nullptr;
	for (TBatchSlot& slot : m_batch)
		if (slot.obs == &obs && !slot.taken)
		{
			slot.taken = true;
			if (slot.ran && slot.prepared.sameInputs(prep))
				ahead = &slot;
			else
			{
				// Its first run counts for nothing: not for the ramp patches
				// its pipeline remembers either.
				if (slot.ran) pipeline.rewindPatches();
				m_parallelStats.run_again++;
			}
			break;
		}
	if (ahead)
	{
		m_parallelStats.ran_ahead++;
		m_parallelStats.on_worker += ahead->onWorker;
		if (ahead->error) std::rethrow_exception(ahead->error);
		const gam::StageTimes& st = pipeline.result().ms;
		aheadMs = st.projection + st.outliers + st.ground + st.ism + st.missing;
	}
	else
		pipeline.process(frame, prep.robot, prep.lattice);
	{
		TCameraInfo& cam = m_cameras[obs.sensorLabel];
		const gam::FrameResult& res = pipeline.result();
		cam.model = res.camera;
		cam.trust_range = res.trust_range;
		cam.height = frame.sensor_position.z() - robotPose.z();
		cam.width = frame.intrinsics.width;
		cam.height_px = frame.intrinsics.height;
		cam.dead_border_columns = int(res.missing.dead_border_columns);
	}
	if (m_options.mount.enabled)
	{
		// The floor in the sensor's own frame says where the sensor is: compare
		// with the declared mount (whatever pose placed the points).
		std::optional<gam::SensorMount> measured;
		const gam::GroundDetection& det = pipeline.result().detection;
		if (det.ok() && !det.planes.empty())
		{
			const mrpt::poses::CPose3D w = robotPose + used;
			Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
			T.linear() = w.getRotationMatrix().asEigen();
			T.translation() = Eigen::Vector3d(w.x(), w.y(), w.z());
			// The sensor's distance to the floor is its height (the robot's
			// origin is on the floor, so the declared z is a height too).
			measured =
				gam::mountFromFloor(gam::planeInSensorFrame(det.ground_from_mount ? det.tree_plane : det.plane(), T));
		}
		mon->second.update({declared.z(), declared.pitch(), declared.roll()}, measured);
	}
	const auto t1 = clk::now();
	applyEvidence(pipeline);
	if (m_options.obstacle_decay_s > 0 && obs.timestamp != INVALID_TIMESTAMP)
	{
		// Positive obstacles of this frame are fresh; cells that were judged a
		// hole, a drop or missing floor never decay.
		const double t = mrpt::Clock::toDouble(obs.timestamp);
		const auto& g = pipeline.frameGrid().geometry();
		const auto& cls = pipeline.ism().classes();
		const auto& ev = pipeline.ism().evidence();
		const auto& missing = pipeline.missingFloor();
		for (uint32_t c : pipeline.ism().evidenceCells())
		{
			const int wx = x2idx(g.cx(int(c % uint32_t(g.nx)))), wy = y2idx(g.cy(int(c / uint32_t(g.nx))));
			if (ev[c] <= 0.5f) continue;
			// (A missing-floor cell has no sample, so it is never of class Obstacle.)
			if (c < cls.size() && cls[c] == gam::VoxelClass::Obstacle)
				notePositive(wx, wy, t);
			else
				noteNegative(wx, wy);
		}
		for (uint32_t c : missing.cells())
			noteNegative(x2idx(g.cx(int(c % uint32_t(g.nx)))), y2idx(g.cy(int(c / uint32_t(g.nx)))));
		decayObstacles(t);
	}
	const auto t2 = clk::now();

	m_times.update = std::chrono::duration<double, std::milli>(t2 - t1).count();
	// (A pipeline that ran ahead, concurrently: its own time counts.)
	m_times.total = std::chrono::duration<double, std::milli>(t2 - t0).count() + aheadMs;
	// A frame is "inserted" even if it found no ground: it was processed, and
	// lastFrame() says why nothing changed.
	return true;
}

void CGroundAwareOccupancyGrid::runBatchSlot(void* grid, size_t i)
{
	auto& self = *static_cast<CGroundAwareOccupancyGrid*>(grid);
	TBatchSlot& slot = self.m_batch[i];
	slot.onWorker = std::this_thread::get_id() != self.m_batchCaller;
	const TPreparedFrame& p = slot.prepared;
	try
	{
		p.pipeline->process(p.frame, p.robot, p.lattice);
	}
	catch (...)
	{
		// Thrown again where insertObservation() would have thrown it.
		slot.error = std::current_exception();
	}
	slot.ran = true;
}

bool CGroundAwareOccupancyGrid::insertObservations(
	const std::vector<const mrpt::obs::CObservation*>& observations, const mrpt::poses::CPose3D& robotPose,
	const std::function<void(size_t)>& afterEach)
{
	using namespace mrpt::obs;
	m_batch.clear();
	if (m_options.threads > 1 && genericMapParams.enableObservationInsertion)
	{
		// The first depth frame of each label runs ahead on the grid as it is
		// now; a second frame of a label needs the first's mount update and
		// the same pipeline, so it runs in order.
		for (const CObservation* o : observations)
		{
			if (!o || !(IS_CLASS(*o, CObservation3DRangeScan) || IS_CLASS(*o, CObservationPointCloud))) continue;
			if (std::any_of(m_batch.begin(), m_batch.end(), [&](const TBatchSlot& b) {
					return b.obs->sensorLabel == o->sensorLabel;
				}))
				continue;
			TBatchSlot& slot = m_batch.emplace_back();
			slot.obs = o;
			try
			{
				prepareFrame(*o, robotPose, slot.prepared);
			}
			catch (const std::exception&)
			{
				// A malformed frame: insertObservation() throws it in its turn.
				m_batch.pop_back();
			}
		}
		m_batchCaller = std::this_thread::get_id();
		if (m_batch.size() > 1)
			m_pool.run(m_batch.size(), &CGroundAwareOccupancyGrid::runBatchSlot, this);
		else
			m_batch.clear();  // nothing to overlap
	}
	bool inserted = false;
	try
	{
		for (size_t i = 0; i < observations.size(); i++)
		{
			if (!observations[i]) continue;
			inserted |= insertObservation(*observations[i], robotPose);
			if (afterEach) afterEach(i);
		}
	}
	catch (...)
	{
		m_batch.clear();
		throw;
	}
	m_batch.clear();
	return inserted;
}

bool CGroundAwareOccupancyGrid::insertObservations(
	const mrpt::obs::CSensoryFrame& sf, const mrpt::poses::CPose3D& robotPose)
{
	m_sfObservations.clear();
	for (const auto& o : sf) m_sfObservations.push_back(o.get());
	return insertObservations(m_sfObservations, robotPose);
}

void CGroundAwareOccupancyGrid::syncMissingLayer() const { syncLayer(m_missingLayer); }

void CGroundAwareOccupancyGrid::syncLayer(COccupancyGridMap2D& L) const
{
	if (L.getSizeX() == getSizeX() && L.getSizeY() == getSizeY() && L.getXMin() == getXMin() &&
		L.getYMin() == getYMin() && L.getResolution() == getResolution())
		return;
	// Same lattice as this grid (MRPT keeps the alignment when a grid grows or
	// is recentred): keep the cells both cover. (Resized in place: assigning
	// whole COccupancyGridMap2D objects is avoided.)
	const unsigned osx = L.getSizeX(), osy = L.getSizeY();
	const float ox = L.getXMin(), oy = L.getYMin(), ores = L.getResolution();
	const std::vector<cellType> old = L.getRawMap();
	L.setSize(getXMin(), getXMax(), getYMin(), getYMax(), getResolution(), 0.5f);
	if (ores != getResolution()) return;
	for (unsigned cy = 0; cy < osy; cy++)
		for (unsigned cx = 0; cx < osx; cx++)
		{
			const int nx = L.x2idx(ox + (cx + 0.5f) * ores), ny = L.y2idx(oy + (cy + 0.5f) * ores);
			if (nx < 0 || ny < 0 || nx >= int(L.getSizeX()) || ny >= int(L.getSizeY())) continue;
			L.getRow(ny)[nx] = old[size_t(cy) * osx + cx];
		}
}

namespace
{
// A world cell index pair, independent of the grid's extent (floor(x / res)),
// packed in one key.
int64_t worldKey(int64_t ix, int64_t iy) { return (ix << 32) ^ (iy & 0xffffffffLL); }
}  // namespace

int64_t CGroundAwareOccupancyGrid::worldKeyOf(int cx, int cy) const
{
	const double r = getResolution();
	return worldKey(
		std::llround(std::floor(idx2x(unsigned(cx)) / r)), std::llround(std::floor(idx2y(unsigned(cy)) / r)));
}

void CGroundAwareOccupancyGrid::notePositive(int cx, int cy, double t) { m_positiveSeen[worldKeyOf(cx, cy)] = t; }

void CGroundAwareOccupancyGrid::noteNegative(int cx, int cy) { m_positiveSeen.erase(worldKeyOf(cx, cy)); }

void CGroundAwareOccupancyGrid::decayObstacles(double t)
{
	const double r = getResolution();
	for (auto it = m_positiveSeen.begin(); it != m_positiveSeen.end();)
	{
		if (t - it->second <= m_options.obstacle_decay_s)
		{
			++it;
			continue;
		}
		const int64_t ix = it->first >> 32, iy = int64_t(int32_t(it->first & 0xffffffffLL));
		const int cx = x2idx((ix + 0.5) * r), cy = y2idx((iy + 0.5) * r);
		// Only an obstacle returns to unknown; a cell seen free since stays free.
		if (cx >= 0 && cy >= 0 && cx < int(getSizeX()) && cy < int(getSizeY()))
		{
			cellType& cell = m_map[size_t(cx) + size_t(cy) * getSizeX()];
			if (cell < 0) cell = 0;
		}
		it = m_positiveSeen.erase(it);
	}
	m_likelihoodCacheOutDated = true;
}

const COccupancyGridMap2D& CGroundAwareOccupancyGrid::missingFloorLayer() const
{
	syncMissingLayer();
	return m_missingLayer;
}

bool CGroundAwareOccupancyGrid::isMissingFloor(float x, float y) const
{
	const COccupancyGridMap2D& L = missingFloorLayer();
	const int cx = L.x2idx(x), cy = L.y2idx(y);
	if (cx < 0 || cy < 0 || cx >= int(L.getSizeX()) || cy >= int(L.getSizeY())) return false;
	return L.getCell(unsigned(cx), unsigned(cy)) < 0.5f;
}

void CGroundAwareOccupancyGrid::applyEvidence(const gam::GroundAwarePipeline& pipeline)
{
	const gam::InverseSensorModel& ism = pipeline.ism();
	const gam::MissingFloorDetector& missing = pipeline.missingFloor();
	const auto& cells = ism.evidenceCells();
	const auto& missingCells = missing.cells();
	if (cells.empty() && missingCells.empty()) return;
	const auto& ev = ism.evidence();
	const auto& g = pipeline.frameGrid().geometry();

	// Grow the grid to hold the evidence (MRPT keeps the cell alignment).
	int x0 = g.nx, x1 = -1, y0 = g.ny, y1 = -1;
	const auto extend = [&](uint32_t c) {
		const int cx = int(c % uint32_t(g.nx)), cy = int(c / uint32_t(g.nx));
		x0 = std::min(x0, cx);
		x1 = std::max(x1, cx);
		y0 = std::min(y0, cy);
		y1 = std::max(y1, cy);
	};
	for (uint32_t c : cells) extend(c);
	for (uint32_t c : missingCells) extend(c);
	const float bx0 = float(g.x_min + x0 * g.resolution), bx1 = float(g.x_min + (x1 + 1) * g.resolution);
	const float by0 = float(g.y_min + y0 * g.resolution), by1 = float(g.y_min + (y1 + 1) * g.resolution);
	if (bx0 < getXMin() || bx1 > getXMax() || by0 < getYMin() || by1 > getYMax())
	{
		// A robot pose far from everything seen so far (corrupt odometry) would
		// otherwise grow the grid to terabytes.
		gam::maps::checkGridSize(
			"growing the ground-aware grid to the robot pose", std::min(bx0, getXMin()), std::max(bx1, getXMax()),
			std::min(by0, getYMin()), std::max(by1, getYMax()), getResolution());
	}
	if (bx0 < getXMin() || bx1 > getXMax() || by0 < getYMin() || by1 > getYMax())
		resizeGrid(
			std::min(bx0, getXMin()), std::max(bx1, getXMax()), std::min(by0, getYMin()), std::max(by1, getYMax()),
			0.5f, true);

	// Log-odds fusion: each cell gets one update per frame. MRPT cells hold
	// the log-odds of being FREE, so occupied evidence lowers them. Missing
	// floor within the block range is obstacle evidence of the obstacle gain
	// (eq. 5 at full density confidence), combined with the ISM's.
	const float pMissing = float(0.5 + 0.5 * m_options.pipeline.ism.K_m);
	const int sx = int(getSizeX()), sy = int(getSizeY());
	syncLayer(m_scanOnlyLayer);
	syncMissingLayer();
	// A frame cell's grid cell, by column and row: x2idx() divides, and a
	// frame has thousands of evidence cells in a few hundred columns and rows.
	// (The same calls as per cell, so the same cells.)
	m_colOf.resize(size_t(g.nx));
	m_layerColOf.resize(size_t(g.nx));
	for (int cx = 0; cx < g.nx; cx++)
	{
		m_colOf[size_t(cx)] = x2idx(g.cx(cx));
		m_layerColOf[size_t(cx)] = m_missingLayer.x2idx(g.cx(cx));
	}
	m_rowOf.resize(size_t(g.ny));
	m_layerRowOf.resize(size_t(g.ny));
	for (int cy = 0; cy < g.ny; cy++)
	{
		m_rowOf[size_t(cy)] = y2idx(g.cy(cy));
		m_layerRowOf[size_t(cy)] = m_missingLayer.y2idx(g.cy(cy));
	}
	const uint32_t nx = uint32_t(g.nx);
	cellType* scanLedger = m_scanOnlyLayer.getRow(0);
	const auto update = [&](uint32_t c, float pOcc) {
		const uint32_t cy = c / nx, cx = c - cy * nx;
		const int wx = m_colOf[cx], wy = m_rowOf[cy];
		if (wx < 0 || wy < 0 || wx >= sx || wy >= sy) return;
		const float pFree = std::clamp(1.0f - pOcc, gam::ism::kEvidenceFloor, 1.0f - gam::ism::kEvidenceFloor);
		const int l = int(p2l(pFree));
		// What the camera marks, no 2D scan takes back: the scans' hits there
		// become part of the cell's base (their ledger starts again at 0).
		if (pOcc > 0.5f) scanLedger[size_t(wx) + size_t(wy) * getSizeX()] = 0;
		cellType& cell = m_map[size_t(wx) + size_t(wy) * getSizeX()];
		cell = cellType(std::clamp(int(cell) + l, int(OCCGRID_CELLTYPE_MIN), int(OCCGRID_CELLTYPE_MAX)));
	};
	// (No missing floor where a ramp or landing patch applies: the detector
	// leaves those cells out, MissingFloorDetector::compute.)
	for (uint32_t c : cells) update(c, missing.isBlocking(c) ? gam::ism::combine(ev[c], pMissing) : ev[c]);
	for (uint32_t c : missing.blockingCells())
		if (ev[c] == 0.5f) update(c, pMissing);

	// The missing-floor layer: this frame's judgement replaces the old one;
	// floor seen clears a cell.
	const auto& cls = ism.classes();
	const auto setLayer = [&](uint32_t c, float pFree) {
		const uint32_t cy = c / nx, cx = c - cy * nx;
		const int wx = m_layerColOf[cx], wy = m_layerRowOf[cy];
		if (wx < 0 || wy < 0 || wx >= sx || wy >= sy) return;
		m_missingLayer.setCell(unsigned(wx), unsigned(wy), pFree);
	};
	for (uint32_t c : cells)
		if (c < cls.size() && cls[c] == gam::VoxelClass::Ground) setLayer(c, 1.0f);
	for (uint32_t c : missingCells) setLayer(c, 0.0f);
	m_is_empty = false;
	m_likelihoodCacheOutDated = true;
}

// ---------------------------------------------------------------------------
// Serialization: v0 = base grid (with its own version) + groundOptions as
// (key, value) pairs, so options added later read back old files.
// v1 = v0 + the missing-floor layer (a plain COccupancyGridMap2D).
// v2 = v1 + the number of depth frames received (scan_keeps_3d_obstacles = auto).
uint8_t CGroundAwareOccupancyGrid::serializeGetVersion() const { return 2; }

void CGroundAwareOccupancyGrid::serializeTo(mrpt::serialization::CArchive& out) const
{
	out << COccupancyGridMap2D::serializeGetVersion();
	COccupancyGridMap2D::serializeTo(out);
	gam::maps::ini::write(m_options, out);
	syncMissingLayer();
	out << m_missingLayer;
	out << m_depthFrames;
}

void CGroundAwareOccupancyGrid::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		case 1:
		case 2: {
			uint8_t baseVer;
			in >> baseVer;
			COccupancyGridMap2D::serializeFrom(in, baseVer);
			TGroundAwareOptions o;
			gam::maps::ini::read(o, in, "CGroundAwareOccupancyGrid");
			setGroundOptions(o);
			resetRunState();
			if (version >= 1) in >> m_missingLayer;
			syncMissingLayer();
			// A map saved before v2 was made by this class's walker rule as it
			// then was (always on): it counts as having seen depth frames.
			m_depthFrames = 1;
			if (version >= 2) in >> m_depthFrames;
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}
