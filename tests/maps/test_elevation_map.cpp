// CElevation25DMap: insertion paths, filters, outputs.
#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/system/filesystem.h>

#include "synthetic_scene.h"

using namespace mrpt::maps;
using mrpt::DEG2RAD;
using mrpt::poses::CPose3D;

TEST(ElevationMap, DepthFrameHeightsMatchTheScene)
{
	// Floor at 0 and a 0.3 m tall box at x 2.0-2.4: cells hold the right heights.
	std::vector<testscene::Box> s = {{-1, -3, -0.1, 6, 3, 0.0}, {2.0, -0.2, 0.0, 2.4, 0.2, 0.3}};
	CElevation25DMap m(-1, 5, -3, 3, 0.05);
	ASSERT_TRUE(m.insertObservation(*testscene::renderDepth(s, CPose3D(0, 0, 1.0, 0, DEG2RAD(25.0), 0), {}, 512, 424)));
	const auto& g = m.grid();
	const auto& floor = g.cell(g.geometry().ix(1.2), g.geometry().iy(0.5));
	ASSERT_TRUE(floor.observed());
	EXPECT_NEAR(floor.z_max, 0.0, 0.003);
	EXPECT_NEAR(floor.z_min, 0.0, 0.003);
	const auto& top = g.cell(g.geometry().ix(2.2), g.geometry().iy(0.0));
	ASSERT_TRUE(top.observed());
	EXPECT_NEAR(top.z_max, 0.3, 0.003);
	// The front face column holds the face from the floor up to the top.
	const auto& face = g.cell(g.geometry().ix(2.01), g.geometry().iy(0.0));
	EXPECT_NEAR(face.z_max, 0.3, 0.01);
	EXPECT_LT(face.z_min, 0.05);
	float lo, hi;
	ASSERT_TRUE(m.getMinMaxHeight(lo, hi));
	EXPECT_NEAR(hi, 0.3, 0.003);
}

TEST(ElevationMap, TwoDScanAndPointCloudInsertion)
{
	CElevation25DMap m(-5, 5, -5, 5, 0.1);
	mrpt::obs::CObservation2DRangeScan s;
	s.aperture = float(M_PI / 2);
	s.maxRange = 50;
	s.sensorPose = CPose3D(0, 0, 0.3, 0, 0, 0);
	s.resizeScanAndAssign(91, 2.0f, true);
	EXPECT_TRUE(m.insertObservation(s, CPose3D(1.0, 0, 0, 0, 0, 0)));
	// The arc of radius 2 around (1, 0) at z = 0.3.
	const auto& c = m.grid().cell(m.grid().geometry().ix(3.0 - 1e-6), m.grid().geometry().iy(0.01));
	ASSERT_TRUE(c.observed());
	EXPECT_NEAR(c.z_max, 0.3, 1e-4);

	CSimplePointsMap pts;
	pts.insertPoint(-2.02f, -2.02f, 1.5f);
	pts.insertPoint(-2.03f, -2.03f, 1.7f);
	EXPECT_EQ(m.insertPointCloud(pts), 2u);
	const auto& p = m.grid().cell(m.grid().geometry().ix(-2.02), m.grid().geometry().iy(-2.02));
	EXPECT_EQ(p.count, 2u);
	EXPECT_FLOAT_EQ(p.z_min, 1.5f);
	EXPECT_FLOAT_EQ(p.z_max, 1.7f);
	// Outside the grid or the z band: dropped.
	CSimplePointsMap out;
	out.insertPoint(9, 9, 0);
	out.insertPoint(0, 0, 99);
	EXPECT_EQ(m.insertPointCloud(out), 0u);
}

TEST(ElevationMap, OutlierFilterAndIdwOptions)
{
	// 40 samples spread over +-1 cm and one spike at +0.5 m in one cell.
	CSimplePointsMap pts;
	for (int i = 0; i < 40; i++) pts.insertPoint(0.02f, 0.02f, 0.01f * float((i % 5) - 2) / 2.0f);
	pts.insertPoint(0.02f, 0.02f, 0.5f);
	pts.insertPoint(0.22f, 0.02f, 0.2f);  // a second cell, 0.2 m from the first
	CElevation25DMap on(-1, 1, -1, 1, 0.1), off(-1, 1, -1, 1, 0.1);
	auto offOpts = off.insertionOptions(), onOpts = on.insertionOptions();
	offOpts.outliers.enabled = false;
	onOpts.idw.radius_cells = 2;
	off.setInsertionOptions(offOpts);
	on.setInsertionOptions(onOpts);
	on.insertPointCloud(pts);
	off.insertPointCloud(pts);
	const auto& g = on.grid().geometry();
	EXPECT_NEAR(on.grid().cell(g.ix(0.02), g.iy(0.02)).z_max, 0.01, 1e-6);
	EXPECT_EQ(on.grid().cell(g.ix(0.02), g.iy(0.02)).count, 40u);
	EXPECT_NEAR(off.grid().cell(g.ix(0.02), g.iy(0.02)).z_max, 0.5, 1e-6);
	EXPECT_EQ(off.grid().cell(g.ix(0.02), g.iy(0.02)).count, 41u);
	// IDW: the empty cell between them (0.12, 0.02) at distance 1 from both:
	// equal weights, so the mean of the two cell means (0 and 0.2).
	const auto& mid = on.grid().cell(g.ix(0.12), g.iy(0.02));
	EXPECT_EQ(mid.count, 0u);
	// min_neighbours = 3 by default: two observed cells are not enough.
	EXPECT_TRUE(std::isnan(mid.z_idw));
	onOpts.idw.min_neighbours = 2;
	on.setInsertionOptions(onOpts);
	on.insertPointCloud(CSimplePointsMap());  // re-runs IDW
	EXPECT_NEAR(on.grid().cell(g.ix(0.12), g.iy(0.02)).z_idw, 0.1, 1e-5);
}

TEST(ElevationMap, PicturesAndVisualization)
{
	std::vector<testscene::Box> s = {{-1, -3, -0.1, 6, 3, 0.0}, {2.0, -0.2, 0.0, 2.4, 0.2, 0.3}};
	CElevation25DMap m(-1, 5, -3, 3, 0.05);
	m.insertObservation(*testscene::renderDepth(s, CPose3D(0, 0, 1.0, 0, DEG2RAD(25.0), 0)));
	const std::string prefix = mrpt::system::getTempFileName() + "_elev";
	m.saveMetricMapRepresentationToFile(prefix);
	mrpt::img::CImage zmax;
	ASSERT_TRUE(zmax.loadFromFile(prefix + "_zmax.png"));
	EXPECT_EQ(zmax.getWidth(), 120u);
	EXPECT_EQ(zmax.getHeight(), 120u);
	// Pixel of an observed cell is coloured, an unobserved one black (+y up).
	const auto& g = m.grid().geometry();
	auto px = [&](double x, double y) {
		const int c = g.ix(x), r = g.ny - 1 - g.iy(y);
		const uint8_t* p = zmax(c, r);
		return int(p[0]) + int(p[1]) + int(p[2]);
	};
	EXPECT_GT(px(2.2, 0.0), 0);
	EXPECT_EQ(px(-0.5, 0.0), 0);
	for (const char* suf : {"_span.png", "_count.png", "_scale.txt"})
		EXPECT_TRUE(mrpt::system::fileExists(prefix + suf)) << suf;

	mrpt::opengl::CSetOfObjects scene;
	m.getVisualizationInto(scene);
	ASSERT_EQ(scene.size(), 1u);
	auto tris = std::dynamic_pointer_cast<mrpt::opengl::CSetOfTriangles>(*scene.begin());
	ASSERT_TRUE(tris);
	EXPECT_EQ(tris->getTrianglesCount(), 10 * m.grid().observedCount());
	m.genericMapParams.enableSaveAs3DObject = false;
	mrpt::opengl::CSetOfObjects none;
	m.getVisualizationInto(none);
	EXPECT_EQ(none.size(), 0u);
}
