// Ground-aware mapping for MRPT -- ground-aware-viewer, the GUI-free part.
#include "ViewerScene.h"

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
#include <sstream>
#include <stdexcept>

#include "gam/mapper/Mapper.h"
#include "gam/mapper/RawlogFrames.h"

using mrpt::maps::CGroundAwareOccupancyGrid;
using mrpt::maps::CHeightBandOccupancyGrid;
using mrpt::maps::COctoMapGrid2D;

namespace gam::viewer
{
// ---------------------------------------------------------------------------
// Views
// ---------------------------------------------------------------------------
const char* viewName(View v)
{
	switch (v)
	{
		case View::Frame3D: return "frame";
		case View::Map3D: return "map";
		case View::Grids: return "grids";
		case View::GridGroundAware: return "grid_ground_aware";
		case View::GridHeightBand: return "grid_height_band";
		case View::GridOctomap: return "grid_octomap";
	}
	return "view";
}

std::vector<View> allViews()
{
	return {View::Frame3D, View::Map3D, View::Grids, View::GridGroundAware, View::GridHeightBand, View::GridOctomap};
}

Box gridViewBox(const ViewerModel& m)
{
	const auto& g = m.groundAware();
	int cx0 = int(g.getSizeX()), cx1 = -1, cy0 = int(g.getSizeY()), cy1 = -1;
	for (int cy = 0; cy < int(g.getSizeY()); cy++)
		for (int cx = 0; cx < int(g.getSizeX()); cx++)
			if (g.getCell(cx, cy) != 0.5f)
			{
				cx0 = std::min(cx0, cx), cx1 = std::max(cx1, cx);
				cy0 = std::min(cy0, cy), cy1 = std::max(cy1, cy);
			}
	const double r = g.getResolution();
	Box b;
	const auto p = m.currentPose();
	if (cx1 < 0)
	{
		b.x0 = p.x() - 3, b.x1 = p.x() + 3, b.y0 = p.y() - 3, b.y1 = p.y() + 3;
	}
	else
	{
		// include the robot, 0.5 m margin; cell-aligned
		const double m_ = 0.5;
		b.x0 = std::min(g.idx2x(cx0) - 0.5 * r, p.x()) - m_;
		b.x1 = std::max(g.idx2x(cx1) + 0.5 * r, p.x()) + m_;
		b.y0 = std::min(g.idx2y(cy0) - 0.5 * r, p.y()) - m_;
		b.y1 = std::max(g.idx2y(cy1) + 0.5 * r, p.y()) + m_;
	}
	// snap to the ground-aware grid's cell borders
	const double ox = g.getXMin(), oy = g.getYMin();
	b.x0 = ox + std::floor((b.x0 - ox) / r) * r;
	b.y0 = oy + std::floor((b.y0 - oy) / r) * r;
	b.x1 = ox + std::ceil((b.x1 - ox) / r) * r;
	b.y1 = oy + std::ceil((b.y1 - oy) / r) * r;
	return b;
}

namespace
{
using namespace mrpt::opengl;
using mrpt::img::TColor;

/** The grid cells inside `b` as a texture (row 0 = lowest y): grey = free
 * probability, never-observed cells (exactly 0.5) light blue. */
CTexturedPlane::Ptr gridTexture(const mrpt::maps::COccupancyGridMap2D& g, const Box& b, double res, double dx)
{
	const int W = std::max(1, int(std::lround(b.w() / res)));
	const int H = std::max(1, int(std::lround(b.h() / res)));
	mrpt::img::CImage img(W, H, mrpt::img::CH_RGB);
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
		{
			const double x = b.x0 + (c + 0.5) * res, y = b.y0 + (r + 0.5) * res;
			const int cx = g.x2idx(x), cy = g.y2idx(y);
			TColor col(200, 220, 255);
			if (cx >= 0 && cy >= 0 && cx < int(g.getSizeX()) && cy < int(g.getSizeY()))
			{
				const float p = g.getCell(cx, cy);
				if (p != 0.5f)
				{
					const uint8_t v = uint8_t(std::lround(255.0 * p));
					col = TColor(v, v, v);
				}
			}
			img.setPixel(c, r, col);
		}
	auto tp = CTexturedPlane::Create();
	tp->setPlaneCorners(float(b.x0 + dx), float(b.x1 + dx), float(b.y0), float(b.y1));
	tp->assignImage(img);
	tp->CRenderizableShaderTexturedTriangles::enableLight(false);
	tp->enableTextureLinearInterpolation(false);
	return tp;
}

/** Orthographic top view of box (x0..x1 wide) fitting a W/H = aspect image.
 * MRPT's orthographic camera shows a height of zoom/2 (width zoom/2 * aspect)
 * when aspect >= 1, and a width of zoom/2 otherwise. */
double orthoVisibleHeight(const Box& b, double aspect) { return std::max(b.h(), b.w() / aspect) * 1.02; }

void setTopCamera(CCamera& cam, const Box& b, double aspect)
{
	const double vh = orthoVisibleHeight(b, aspect);
	cam.setOrthogonal(true);
	cam.setPointingAt(float(0.5 * (b.x0 + b.x1)), float(0.5 * (b.y0 + b.y1)), 0.f);
	cam.setAzimuthDegrees(-90.f);
	cam.setElevationDegrees(90.f);
	cam.setZoomDistance(float(aspect >= 1 ? 2.0 * vh : 2.0 * vh * aspect));
}

TColor classColour(gam::VoxelClass c)
{
	switch (c)
	{
		case gam::VoxelClass::Ground: return {40, 190, 60};
		case gam::VoxelClass::Obstacle: return {230, 40, 30};
		case gam::VoxelClass::Drop: return {200, 40, 220};
		case gam::VoxelClass::OutOfRange: return {90, 90, 90};
		default: return {70, 120, 230};
	}
}

void addQuad(
	CSetOfTriangles& t, const mrpt::math::TPoint3Df& a, const mrpt::math::TPoint3Df& b, const mrpt::math::TPoint3Df& c,
	const mrpt::math::TPoint3Df& d, const TColor& col)
{
	TTriangle t1(a, b, c), t2(a, c, d);
	for (auto* tr : {&t1, &t2})
		for (auto& v : tr->vertices) v.setColor(col);
	t.insertTriangle(t1);
	t.insertTriangle(t2);
}

CPointCloudColoured::Ptr cloudOf(const std::vector<mrpt::math::TPoint3Df>& pts)
{
	auto pc = CPointCloudColoured::Create();
	float z0 = 1e9f, z1 = -1e9f;
	for (const auto& p : pts) z0 = std::min(z0, p.z), z1 = std::max(z1, p.z);
	for (const auto& p : pts)
	{
		const float t = z1 > z0 ? (p.z - z0) / (z1 - z0) : 0.5f;
		const auto c = mrpt::img::colormap(mrpt::img::cmJET, t);
		pc->push_back(p.x, p.y, p.z, c.R, c.G, c.B);
	}
	pc->setPointSize(2.f);
	return pc;
}

void addFrame3D(const ViewerModel& m, COpenGLScene& scene)
{
	const auto& ga = m.groundAware();
	const auto& d = ga.lastFrame();
	scene.insert(cloudOf(m.framePoints()));
	if (m.current() < 0 || !m.step(size_t(m.current())).has3D || !d.valid) return;

	// 2.5D voxels: one column per observed cell, coloured by ISM class
	const auto& eg = ga.lastFrameElevation();
	const auto& geo = eg.geometry();
	const auto& cls = ga.lastFrameIsm().classes();
	auto tri = CSetOfTriangles::Create();
	const float h = float(0.5 * geo.resolution * 0.9);
	for (uint32_t idx : eg.observedCells())
	{
		const auto& c = eg.cell(idx);
		const int cx = int(idx % uint32_t(geo.nx)), cy = int(idx / uint32_t(geo.nx));
		const float x = float(geo.cx(cx)), y = float(geo.cy(cy));
		const float z0 = c.z_min, z1 = std::max(c.z_max, c.z_min + 0.01f);
		const TColor col = classColour(idx < cls.size() ? cls[idx] : gam::VoxelClass::None);
		using P = mrpt::math::TPoint3Df;
		addQuad(*tri, P(x - h, y - h, z1), P(x + h, y - h, z1), P(x + h, y + h, z1), P(x - h, y + h, z1), col);
		if (z1 - z0 > 0.02f)
		{
			const TColor side(uint8_t(col.R * 0.7), uint8_t(col.G * 0.7), uint8_t(col.B * 0.7));
			addQuad(*tri, P(x - h, y - h, z0), P(x + h, y - h, z0), P(x + h, y - h, z1), P(x - h, y - h, z1), side);
			addQuad(*tri, P(x + h, y - h, z0), P(x + h, y + h, z0), P(x + h, y + h, z1), P(x + h, y - h, z1), side);
			addQuad(*tri, P(x + h, y + h, z0), P(x - h, y + h, z0), P(x - h, y + h, z1), P(x + h, y + h, z1), side);
			addQuad(*tri, P(x - h, y + h, z0), P(x - h, y - h, z0), P(x - h, y - h, z1), P(x - h, y + h, z1), side);
		}
	}
	tri->enableLight(false);
	scene.insert(tri);

	const auto& det = d.detection;
	// ground plane(s): a translucent patch over the nodes supporting each
	for (size_t k = 0; k < det.planes.size(); k++)
	{
		const auto& pl = det.planes[k];
		if (std::abs(pl.c) < 1e-6) continue;
		double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
		for (const auto& n : det.nodes)
			if (k == 0 || n.plane_id == int(k))
				x0 = std::min<double>(x0, n.x), x1 = std::max<double>(x1, n.x), y0 = std::min<double>(y0, n.y),
				y1 = std::max<double>(y1, n.y);
		if (x1 < x0) continue;
		const double mg = k == 0 ? 0.5 : ga.groundOptions().pipeline.ism.plane_support_radius;
		x0 -= mg, x1 += mg, y0 -= mg, y1 += mg;
		auto patch = CSetOfTriangles::Create();
		auto P = [&](double x, double y) {
			return mrpt::math::TPoint3Df(float(x), float(y), float(pl.heightAt(x, y) + 0.005));
		};
		const TColor col = k == 0 ? TColor(60, 130, 255, 90) : TColor(255, 200, 40, 110);
		addQuad(*patch, P(x0, y0), P(x1, y0), P(x1, y1), P(x0, y1), col);
		patch->enableLight(false);
		patch->setColor_u8(col);
		scene.insert(patch);
	}
	// RRT tree
	auto edges = CSetOfLines::Create();
	auto nodes = CPointCloud::Create();
	for (const auto& n : det.nodes)
	{
		nodes->insertPoint(n.x, n.y, n.z + 0.03f);
		if (n.parent >= 0 && size_t(n.parent) < det.nodes.size())
		{
			const auto& q = det.nodes[size_t(n.parent)];
			edges->appendLine(n.x, n.y, n.z + 0.03f, q.x, q.y, q.z + 0.03f);
		}
	}
	edges->setColor_u8(TColor(255, 230, 0));
	edges->setLineWidth(2.f);
	nodes->setColor_u8(TColor(255, 120, 0));
	nodes->setPointSize(5.f);
	scene.insert(edges);
	scene.insert(nodes);
}

void addRobotAndPath(const ViewerModel& m, COpenGLScene& scene)
{
	auto axes = stock_objects::CornerXYZ(0.4f);
	axes->setPose(m.currentPose());
	scene.insert(axes);
	const auto path = m.pathSoFar();
	if (path.size() >= 2)
	{
		auto l = CSetOfLines::Create();
		for (size_t i = 1; i < path.size(); i++)
			l->appendLine(path[i - 1].x(), path[i - 1].y(), 0.02, path[i].x(), path[i].y(), 0.02);
		l->setColor_u8(TColor(0, 200, 255));
		l->setLineWidth(2.f);
		scene.insert(l);
	}
}
}  // namespace

void ViewerScene::build(
	const ViewerModel& m, View v, mrpt::opengl::COpenGLScene& scene, mrpt::opengl::CCamera& cam, double aspect)
{
	scene.clear();
	auto vp = scene.getViewport();
	vp->setViewportClipDistances(0.05f, 500.f);
	const Box box = gridViewBox(m);
	const double res = m.groundAware().getResolution();
	const auto pose = m.currentPose();
	switch (v)
	{
		case View::Frame3D: {
			vp->setCustomBackgroundColor({0.12f, 0.12f, 0.15f});
			auto grid = CGridPlaneXY::Create(
				float(pose.x() - 6), float(pose.x() + 6), float(pose.y() - 6), float(pose.y() + 6), 0, 1);
			grid->setColor_u8(TColor(80, 80, 90));
			scene.insert(grid);
			addFrame3D(m, scene);
			addRobotAndPath(m, scene);
			const auto look = pose + mrpt::poses::CPoint3D(2.2, 0, 0);
			cam.setProjectiveModel(true);
			cam.setPointingAt(float(look.x()), float(look.y()), 0.f);
			cam.setAzimuthDegrees(float(mrpt::RAD2DEG(pose.yaw()) + 180 + 30));
			cam.setElevationDegrees(35.f);
			cam.setZoomDistance(7.5f);
			break;
		}
		case View::Map3D: {
			vp->setCustomBackgroundColor({0.12f, 0.12f, 0.15f});
			// the 2.5D map's columns, with the ground-aware grid underneath them
			float zlo = 0, zhi = 0;
			const bool hasEl = m.elevation().getMinMaxHeight(zlo, zhi);
			auto tex = gridTexture(m.groundAware(), box, res, 0);
			tex->setLocation(0, 0, std::min(0.f, hasEl ? zlo : 0.f) - 0.05);
			scene.insert(tex);
			if (hasEl)
			{
				auto el = CSetOfObjects::Create();
				m.elevation().getVisualizationInto(*el);
				scene.insert(el);
			}
			auto pc = cloudOf(m.mapPoints());
			pc->setPointSize(1.f);
			scene.insert(pc);
			addRobotAndPath(m, scene);
			cam.setProjectiveModel(true);
			cam.setPointingAt(float(0.5 * (box.x0 + box.x1)), float(0.5 * (box.y0 + box.y1)), 0.f);
			cam.setAzimuthDegrees(-90.f);
			cam.setElevationDegrees(55.f);
			cam.setZoomDistance(float(std::max(box.w(), box.h()) * 1.4 * std::max(1.0, 1.33 / aspect)));
			break;
		}
		case View::Grids: {
			vp->setCustomBackgroundColor({0.25f, 0.25f, 0.28f});
			const double gap = 0.05 * box.w() + 0.2;
			const mrpt::maps::COccupancyGridMap2D* gs[3] = {&m.groundAware(), &m.heightBand(), &m.octomap()};
			for (int i = 0; i < 3; i++) scene.insert(gridTexture(*gs[i], box, res, i * (box.w() + gap)));
			Box all = box;
			all.x1 = box.x1 + 2 * (box.w() + gap);
			setTopCamera(cam, all, aspect);
			break;
		}
		case View::GridGroundAware:
		case View::GridHeightBand:
		case View::GridOctomap: {
			vp->setCustomBackgroundColor({0.25f, 0.25f, 0.28f});
			const mrpt::maps::COccupancyGridMap2D& g =
				v == View::GridGroundAware  ? static_cast<const mrpt::maps::COccupancyGridMap2D&>(m.groundAware())
				: v == View::GridHeightBand ? static_cast<const mrpt::maps::COccupancyGridMap2D&>(m.heightBand())
											: static_cast<const mrpt::maps::COccupancyGridMap2D&>(m.octomap());
			scene.insert(gridTexture(g, box, res, 0));
			setTopCamera(cam, box, aspect);
			break;
		}
	}
}

void ViewerScene::gridPixel(const ViewerModel& m, double x, double y, int W, int H, double& col, double& row)
{
	const Box b = gridViewBox(m);
	const double aspect = double(W) / double(H);
	const double vh = orthoVisibleHeight(b, aspect), vw = vh * aspect;
	col = 0.5 * W + (x - 0.5 * (b.x0 + b.x1)) / vw * W;
	row = 0.5 * H - (y - 0.5 * (b.y0 + b.y1)) / vh * H;
}

void ViewerScene::renderToPng(const ViewerModel& m, View v, const std::string& file, int W, int H)
{
	mrpt::opengl::COpenGLScene scene;
	mrpt::opengl::CFBORender render{unsigned(W), unsigned(H)};
	auto& cam = render.getCamera(scene);
	build(m, v, scene, cam, double(W) / double(H));
	mrpt::img::CImage img;
	render.render_RGB(scene, img);
	if (!img.saveToFile(file)) throw std::runtime_error("cannot write " + file);
}

}  // namespace gam::viewer
