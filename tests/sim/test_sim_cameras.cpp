// Ground-aware mapping for MRPT -- tests: the camera models beside the Kinect One
// (active stereo D435/D455, time of flight Femto, structured light Astra).
// Expected values are worked out from the makers' figures quoted in Sensors.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "gam/sim/SceneFile.h"

using namespace gam::sim;

namespace
{
constexpr double kDeg = M_PI / 180;
SceneFile parse(const std::string& txt)
{
	std::stringstream ss("path waypoints=0,0,0\n" + txt);
	return parseScene(ss, "test.scene");
}
/** A camera of this model at the origin, level, looking at a wall at `dist` (no floor). */
SceneFile wallAt(double dist)
{
	SceneFile sf = parse("floor present=0\n");
	sf.scene.solids.push_back(ConvexSolid::box(Pose3::fromXYZYPR(dist + 0.5, 0, 0, 0, 0, 0), {0.5, 50, 50}, 1));
	return sf;
}
const Pose3 kLevel = Pose3::fromXYZYPR(0, 0, 0, 0, 0, 0);
}  // namespace

TEST(SimCameras, PresetsFollowTheMakersFigures)
{
	// D435: 848 px over 87 deg -> fx = 424 / tan(43.5 deg) = 424 / 0.948965 = 446.80 px;
	// sigma_z(2 m) = z^2 * hypot(0.08, 0.05) / (fx * b) = 4 * 0.094340 / (446.80 * 0.050)
	//             = 0.377359 / 22.340 = 16.89 mm (0.84 % of 2 m: inside Intel's "< 2 % at 2 m").
	const KinectParams d435 = cameraPreset(CameraModel::D435);
	EXPECT_EQ(d435.width, 848);
	EXPECT_EQ(d435.height, 480);
	EXPECT_NEAR(d435.fx(), 446.80, 0.01);
	EXPECT_NEAR(d435.sigma(2.0, 0.0), 0.01689, 2e-5);
	// D455: the same optics, baseline 95 mm: sigma_z(4 m) = 16 * 0.094340 / (446.80 * 0.095)
	//       = 1.509440 / 42.446 = 35.56 mm (0.89 % of 4 m: inside "< 2 % at 4 m").
	const KinectParams d455 = cameraPreset(CameraModel::D455);
	EXPECT_NEAR(d455.sigma(4.0, 0.0), 0.03556, 3e-5);
	EXPECT_NEAR(d455.disparity(2.0), 446.80 * 0.095 / 2.0, 1e-2);  // 21.22 px
	// Astra: 640 px over 60 deg -> fx = 320 / tan(30 deg) = 554.26 px; sigma_d = hypot(0.07, 0.03)
	// = 0.076158 px; sigma_z(2 m) = 4 * 0.076158 / (554.26 * 0.075) = 0.304631 / 41.569 = 7.33 mm.
	const KinectParams astra = cameraPreset(CameraModel::Astra);
	EXPECT_NEAR(astra.fx(), 554.26, 0.01);
	EXPECT_NEAR(astra.sigma(2.0, 0.0), 0.00733, 1e-5);
	EXPECT_EQ(astra.max_range, 4.0);
	// Femto: 640x576, 75 x 65 deg; time of flight: the Kinect v2 form,
	// 1.5 - 0.5*2 + 0.3*4 = 1.7 mm at 2 m (the maker's bound is 17 mm).
	const KinectParams femto = cameraPreset(CameraModel::Femto);
	EXPECT_EQ(femto.width, 640);
	EXPECT_EQ(femto.height, 576);
	EXPECT_FALSE(femto.fromDisparity());
	EXPECT_NEAR(femto.sigma(2.0, 0.0), 1.7e-3, 1e-9);
	EXPECT_NEAR(2 * std::atan(0.5 * femto.height / femto.fy()) / kDeg, 65.0, 1e-9);
	// the Kinect One preset is the default
	const KinectParams k1 = cameraPreset(CameraModel::KinectOne), def;
	EXPECT_EQ(k1.width, def.width);
	EXPECT_EQ(k1.sigma(3.0, 0.5), def.sigma(3.0, 0.5));
}

TEST(SimCameras, StereoDepthNoiseGrowsWithTheSquareOfTheRange)
{
	// D435 on a fronto-parallel wall, per-pixel disparity noise only (no correlated
	// field, no quantisation, no spikes): the depth error is sigma_d * z^2 / (fx b)
	// to first order. At 1 m: 0.08 / 22.340 = 3.58 mm; at 3 m: 9 x that = 32.2 mm.
	for (double dist : {1.0, 3.0})
	{
		KinectParams p = cameraPreset(CameraModel::D435);
		p.width = 106;  // a crop of the image: fewer pixels, the same fx
		p.height = 60;
		p.hfov_deg = 2 * std::atan(53.0 / 446.80) / kDeg;  // fx stays 446.80 px
		p.vfov_deg = 2 * std::atan(30.0 / 446.80) / kDeg;
		p.disp_corr_sigma_px = 0;
		p.disp_step_px = 0;
		p.spike_prob = 0;
		ASSERT_NEAR(p.fx(), 446.80, 0.01);
		const KinectModel km(p);
		const SceneFile sf = wallAt(dist);
		std::mt19937 rng(21);
		double s2 = 0;
		size_t n = 0;
		for (int rep = 0; rep < 20; rep++)
		{
			const DepthFrame f = km.render(sf.scene, kLevel, rng);
			for (size_t i = 0; i < f.depth.size(); i++)
			{
				if (!(f.flags[i] & PixValid)) continue;
				const double e = f.depth[i] - f.true_depth[i];
				s2 += e * e;
				n++;
			}
		}
		ASSERT_GT(n, 50000u);
		const double expected = 0.08 * dist * dist / 22.340;
		EXPECT_NEAR(std::sqrt(s2 / n), expected, 0.04 * expected) << "at " << dist << " m";
	}
}

TEST(SimCameras, CorrelatedDisparityNoiseIsSharedByNeighbours)
{
	// With only the correlated field (0.05 px rms over 16 px), horizontally adjacent
	// pixels err almost alike (bilinear: correlation > 0.9 one pixel apart); with only
	// per-pixel noise they are independent (|correlation| < 0.05).
	auto neighbourCorrelation = [](double perPixel, double correlated) {
		KinectParams p = cameraPreset(CameraModel::D435);
		p.disp_sigma_px = perPixel;
		p.disp_corr_sigma_px = correlated;
		p.disp_step_px = 0;
		p.spike_prob = 0;
		p.fatten_px = 0;
		const KinectModel km(p);
		const SceneFile sf = wallAt(2.0);
		std::mt19937 rng(4);
		double sab = 0, saa = 0, sbb = 0;
		for (int rep = 0; rep < 3; rep++)
		{
			const DepthFrame f = km.render(sf.scene, kLevel, rng);
			for (int r = 0; r < f.height; r++)
				for (int c = 0; c + 1 < f.width; c++)
				{
					const size_t i = f.idx(r, c), j = f.idx(r, c + 1);
					if (!(f.flags[i] & PixValid) || !(f.flags[j] & PixValid)) continue;
					const double a = f.depth[i] - f.true_depth[i], b = f.depth[j] - f.true_depth[j];
					sab += a * b;
					saa += a * a;
					sbb += b * b;
				}
		}
		return sab / std::sqrt(saa * sbb);
	};
	EXPECT_GT(neighbourCorrelation(0.0, 0.05), 0.9);
	EXPECT_LT(std::abs(neighbourCorrelation(0.08, 0.0)), 0.05);
}

TEST(SimCameras, DisparityComesInSubPixelSteps)
{
	// Astra, 1/8 px steps and no other noise: every depth is fx b / (k / 8) for an
	// integer k. At 3 m the true disparity is 41.569 / 3 = 13.856 px -> k = round(110.85)
	// = 111 -> 3.0    (41.569 / 13.875 = 2.9960 m): a 4 mm step; the next step is
	// 41.569 / 14.0 = 2.9692 m, 27 mm nearer (steps grow with z^2).
	KinectParams p = cameraPreset(CameraModel::Astra);
	p.disp_sigma_px = 0;
	p.disp_corr_sigma_px = 0;
	p.spike_prob = 0;
	const KinectModel km(p);
	const SceneFile sf = wallAt(3.0);
	std::mt19937 rng(2);
	const DepthFrame f = km.render(sf.scene, kLevel, rng);
	const double fb = p.fx() * p.baseline;
	ASSERT_NEAR(fb, 41.569, 1e-3);
	size_t n = 0;
	for (size_t i = 0; i < f.depth.size(); i++)
	{
		if (!(f.flags[i] & PixValid)) continue;
		const double k = 8.0 * fb / f.depth[i];
		ASSERT_NEAR(k, std::round(k), 1e-3);  // float depth: 1e-3 of a step
		n++;
	}
	EXPECT_GT(n, 200000u);
	const size_t centre = f.idx(f.height / 2, f.width / 2);
	EXPECT_NEAR(f.depth[centre], 41.569 / 13.875, 1e-4);  // 2.9960 m
}

TEST(SimCameras, StereoLeavesAnInvalidBandBesideNearObjects)
{
	// A pole 0.1 m wide at 1 m in front of a wall at 3 m, D435 (fx b = 22.340 px m):
	// disparities 22.34 px (pole) and 7.447 px (wall). The second imager, to the right,
	// does not see the wall for (22.34 - 7.447) = 14.9 px left of the pole, nor the
	// image's first 7.4 columns (c - d < 0). Right of the pole nothing is occluded.
	SceneFile sf = wallAt(3.0);
	sf.scene.solids.push_back(ConvexSolid::box(Pose3::fromXYZYPR(1.05, 0, 0, 0, 0, 0), {0.05, 0.05, 50}, 2));
	KinectParams p = cameraPreset(CameraModel::D435);
	p.fatten_px = 0;
	p.spike_prob = 0;
	const KinectModel km(p);
	std::mt19937 rng(8);
	const DepthFrame f = km.render(sf.scene, kLevel, rng);
	const int r = f.height / 2;
	int poleFirst = -1, poleLast = -1;
	for (int c = 0; c < f.width; c++)
		if (f.object_id[f.idx(r, c)] == 2)
		{
			if (poleFirst < 0) poleFirst = c;
			poleLast = c;
		}
	ASSERT_GT(poleFirst, 100);
	int band = 0, edgeBand = 0;
	for (int c = 0; c < poleFirst; c++)
		if (f.flags[f.idx(r, c)] & PixOccluded) (c < 50 ? edgeBand : band)++;
	EXPECT_NEAR(band, 14.9, 1.5);
	EXPECT_NEAR(edgeBand, 7.4, 1.0);
	for (int c = poleLast + 1; c < f.width; c++) ASSERT_FALSE(f.flags[f.idx(r, c)] & PixOccluded) << "column " << c;
	// the occluded pixels have no depth
	for (int c = 0; c < f.width; c++)
	{
		const size_t i = f.idx(r, c);
		ASSERT_TRUE(!(f.flags[i] & PixOccluded) || f.depth[i] == 0.0f) << "column " << c;
	}
}

TEST(SimCameras, StereoEdgesFattenTowardTheBackground)
{
	// The same pole, fattening on (2 px, prob 0.7): wall pixels 1-2 columns right of
	// the pole take the pole's depth (~1 m) in about 70 % of the rows; 3 columns away, never.
	SceneFile sf = wallAt(3.0);
	sf.scene.solids.push_back(ConvexSolid::box(Pose3::fromXYZYPR(1.05, 0, 0, 0, 0, 0), {0.05, 0.05, 50}, 2));
	KinectParams p = cameraPreset(CameraModel::D435);
	p.spike_prob = 0;
	const KinectModel km(p);
	std::mt19937 rng(9);
	const DepthFrame f = km.render(sf.scene, kLevel, rng);
	size_t near = 0, rows = 0;
	for (int r = 10; r < f.height - 10; r++)
	{
		int poleLast = -1;
		for (int c = 0; c < f.width; c++)
			if (f.object_id[f.idx(r, c)] == 2) poleLast = c;
		ASSERT_GT(poleLast, 0);
		for (int k = 1; k <= 2; k++)
		{
			const size_t i = f.idx(r, poleLast + k);
			rows++;
			if ((f.flags[i] & PixValid) && f.depth[i] < 1.2) near++;
		}
		const size_t far = f.idx(r, poleLast + 3);
		ASSERT_FALSE(f.flags[far] & PixFattened);
	}
	// 0.7 x (1 - grazing/spike losses, none on a fronto-parallel wall)
	EXPECT_NEAR(double(near) / rows, 0.7, 0.05);
}

TEST(SimCameras, TimeOfFlightMultipathPushesTheFloorAwayAtAWallsFoot)
{
	// Femto 1 m up, pitched 30 deg down, a wall 2.5 m ahead. A floor pixel s metres in
	// front of the wall's foot reads 20 mm * exp(-s / 0.3) long along its ray: 20 mm at
	// the foot, 20 * exp(-1) = 7.4 mm at s = 0.3 m, < 0.1 mm beyond s = 1.6 m.
	SceneFile sf = parse("wall id=1 x0=2.5 y0=-5 x1=2.5 y1=5 thickness=0.1\n");
	KinectParams p = cameraPreset(CameraModel::Femto);
	const double sigmaScale = p.noise_scale;
	p.noise_scale = 0;  // the bias alone
	p.flying_prob = 0;
	p.spike_prob = 0;
	p.grazing_start_deg = 89;
	p.grazing_end_deg = 89.5;
	const KinectModel km(p);
	const Pose3 cam = Pose3::fromXYZYPR(0, 0, 1, 0, 30 * kDeg, 0);
	std::mt19937 rng(1);
	const DepthFrame f = km.render(sf.scene, cam, rng);
	size_t checked = 0;
	for (int r = 0; r < f.height; r++)
	{
		const int c = f.width / 2;
		const size_t i = f.idx(r, c);
		if (!(f.flags[i] & PixValid) || f.object_id[i] != 0) continue;
		const Eigen::Vector3d ray = km.pixelRay(r, c);
		const Eigen::Vector3d q = cam.t + f.true_depth[i] * (cam.R * ray);
		const double s = 2.45 - q.x();  // the wall's face is at x = 2.45
		const double extraRange = (f.depth[i] - f.true_depth[i]) * ray.norm();
		EXPECT_NEAR(extraRange, 0.020 * std::exp(-s / 0.3), 1e-4) << "s = " << s;
		if (s > 1.6)
		{
			EXPECT_LT(extraRange, 1e-4);
		}
		checked++;
	}
	EXPECT_GT(checked, 100u);
	EXPECT_EQ(sigmaScale, 1.0);  // the Kinect v2 form at its own scale
}

TEST(SimCameras, ACameraWithoutALabelIsLabelledAfterItsModel)
{
	// The map's camera_model = auto tells a D455 from a D435 by the label only
	// (both 848x480 at 87 deg), so a camera the scene does not label carries its
	// model's name; the Kinect One keeps "KINECT", the label of every older rawlog.
	const std::string pose = "kinect pose=0.1,0,1,0,25,0";
	EXPECT_EQ(parse(pose + "\n").kinect_label, "KINECT");
	EXPECT_EQ(parse(pose + " model=d435\n").kinect_label, "D435");
	EXPECT_EQ(parse(pose + " model=d455\n").kinect_label, "D455");
	EXPECT_EQ(parse(pose + " model=femto\n").kinect_label, "FEMTO");
	EXPECT_EQ(parse(pose + " model=astra\n").kinect_label, "ASTRA");
	// --camera relabels the cameras the scene did not label, and back.
	SceneFile sf = parse(pose + "\n" + pose + " label=DOWN\n");
	setCameraModel(sf, CameraModel::D455);
	EXPECT_EQ(sf.kinect_label, "D455");
	ASSERT_EQ(sf.more_kinects.size(), 1u);
	EXPECT_EQ(sf.more_kinects[0].label, "DOWN");  // the scene's own label stays
	setCameraModel(sf, CameraModel::KinectOne);
	EXPECT_EQ(sf.kinect_label, "KINECT");
	// Two cameras never share a label: the second unlabelled one keeps its own
	// when the model's name is taken by the first.
	SceneFile two = parse(pose + " label=D455\n" + pose + "\n");
	EXPECT_EQ(two.more_kinects[0].label, "KINECT");
	setCameraModel(two, CameraModel::D455);
	EXPECT_EQ(two.kinect_label, "D455");
	EXPECT_EQ(two.more_kinects[0].label, "KINECT");
	try
	{
		parse(pose + " model=d455\n" + pose + " label=D455\n");
		FAIL() << "a label given twice must be an error";
	}
	catch (const SceneError& e)
	{
		EXPECT_NE(std::string(e.what()).find("duplicate camera label 'D455'"), std::string::npos) << e.what();
	}
}

TEST(SimCameras, SceneAndCommandLineChooseTheModel)
{
	const SceneFile sf = parse("kinect pose=0.1,0,1,0,25,0 model=d455 max_range=5\n");
	EXPECT_EQ(sf.kinect.model, CameraModel::D455);
	EXPECT_EQ(sf.kinect.width, 848);
	EXPECT_EQ(sf.kinect.baseline, 0.095);
	EXPECT_EQ(sf.kinect.max_range, 5.0);  // the statement's key over the preset's 6 m
	SceneFile other = sf;
	setCameraModel(other, CameraModel::Astra);
	EXPECT_EQ(other.kinect.model, CameraModel::Astra);
	EXPECT_EQ(other.kinect.width, 640);
	EXPECT_EQ(other.kinect.max_range, 5.0);  // still the statement's
	try
	{
		parse("kinect pose=0.1,0,1,0,25,0 model=d415\n");
		FAIL() << "an unknown model must be an error";
	}
	catch (const SceneError& e)
	{
		EXPECT_NE(std::string(e.what()).find("unknown model 'd415'"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("d435"), std::string::npos) << e.what();
	}
	CameraModel m;
	EXPECT_FALSE(parseCameraModel("D435", m));  // names are lower case, as written
	for (CameraModel x :
		 {CameraModel::KinectOne, CameraModel::D435, CameraModel::D455, CameraModel::Femto, CameraModel::Astra})
	{
		ASSERT_TRUE(parseCameraModel(cameraModelName(x), m));
		EXPECT_EQ(m, x);
	}
}
