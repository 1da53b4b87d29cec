// Ground-aware mapping for MRPT -- ground-aware-viewer: steps through a rawlog
// with the ground-aware grid and the two comparison grids, showing per frame
// the point cloud, the 2.5D voxels, the ground plane, the RRT tree, the grids
// side by side and the stage timings; the ISM / RRT-GPD parameters are
// editable and re-run the current frame. wxWidgets + mrpt::gui canvases.
//
// usage: ground-aware-viewer [--rawlog] FILE.rawlog [--config FILE.ini]
//            [--section map] [--frame N] [--screenshot-dir DIR --exit]
//            [--width 800 --height 600]
// Batch mode (--screenshot-dir DIR --exit) renders every view off-screen with
// CFBORender into DIR/<view>.png and exits: no display needed.
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <gam/maps/IniFields.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/gui/CWxGLCanvasBase.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <wx/dirdlg.h>
#include <wx/filedlg.h>
#include <wx/propgrid/propgrid.h>
#include <wx/slider.h>
#include <wx/splitter.h>
#include <wx/timer.h>
#include <wx/wx.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <variant>

#include "ViewerScene.h"

using gam::viewer::View;
using gam::viewer::ViewerModel;
using gam::viewer::ViewerScene;

namespace
{
struct Args
{
	std::string rawlog, config, section = "map", shotDir, initialMap;
	int frame = -1;  ///< -1 = the last one
	bool exit = false;
	int width = 800, height = 600;
	std::string guiSnapshot;  ///< (self-check) capture the GUI window into this PNG and quit
};

/** Renders every view into dir/<view>.png (+ timings.txt). */
void exportViews(const ViewerModel& m, const std::string& dir, int W, int H, std::ostream& log)
{
	std::filesystem::create_directories(dir);
	for (View v : gam::viewer::allViews())
	{
		const std::string f = dir + "/" + gam::viewer::viewName(v) + ".png";
		ViewerScene::renderToPng(m, v, f, W, H);
		log << "  " << f << "\n";
	}
	std::ofstream(dir + "/timings.txt") << m.statusText();
	log << "  " << dir << "/timings.txt\n";
}

int runBatch(const Args& a)
{
	ViewerModel m;
	m.loadConfig(a.config, a.section);
	if (!a.initialMap.empty()) m.loadInitialMap(a.initialMap);
	m.openRawlog(a.rawlog);
	m.seek(a.frame < 0 ? int(m.stepCount()) - 1 : std::min(a.frame, int(m.stepCount()) - 1));
	std::cout << m.statusText();
	std::cout << "ground-aware-viewer: wrote\n";
	exportViews(m, a.shotDir, a.width, a.height, std::cout);
	return 0;
}

// ---------------------------------------------------------------------------
// GUI
// ---------------------------------------------------------------------------
class ViewCanvas : public mrpt::gui::CWxGLCanvasBase
{
   public:
	ViewCanvas(wxWindow* parent, View v)
		: CWxGLCanvasBase(parent, wxID_ANY, wxDefaultPosition, wxSize(300, 200)), m_view(v)
	{
	}
	View view() const { return m_view; }
	/** Rebuilds the scene; resets the camera if `resetCamera`. */
	void update(const ViewerModel& m, bool resetCamera)
	{
		auto scene = mrpt::opengl::COpenGLScene::Create();
		mrpt::opengl::CCamera cam;
		const wxSize sz = GetClientSize();
		ViewerScene::build(m, m_view, *scene, cam, sz.y > 0 ? double(sz.x) / sz.y : 1.33);
		getOpenGLSceneRef() = scene;
		if (resetCamera)
		{
			setCameraProjective(cam.isProjective());
			const auto p = cam.getPointingAt();
			setCameraPointing(p.x, p.y, p.z);
			setZoomDistance(cam.getZoomDistance());
			setAzimuthDegrees(cam.getAzimuthDegrees());
			setElevationDegrees(cam.getElevationDegrees());
		}
		Refresh(false);
	}

   private:
	View m_view;
};

enum
{
	ID_OPEN = wxID_HIGHEST + 1,
	ID_OPEN_INI,
	ID_OPEN_MAP,
	ID_SAVE_MAP,
	ID_FIRST,
	ID_PREV,
	ID_NEXT,
	ID_LAST,
	ID_PLAY,
	ID_EXPORT,
	ID_FOLLOW,
	ID_SLIDER,
	ID_TIMER
};

class ViewerFrame : public wxFrame
{
   public:
	explicit ViewerFrame(const Args& a)
		: wxFrame(nullptr, wxID_ANY, "ground-aware-viewer", wxDefaultPosition, wxSize(1400, 900)),
		  m_args(a),
		  m_timer(this, ID_TIMER)
	{
		auto* top = new wxPanel(this);
		auto* bar = new wxBoxSizer(wxHORIZONTAL);
		auto btn = [&](int id, const char* label) {
			auto* b = new wxButton(top, id, label, wxDefaultPosition, wxDefaultSize, wxBU_EXACTFIT);
			bar->Add(b, 0, wxALL, 2);
			return b;
		};
		btn(ID_OPEN, "Open rawlog...");
		btn(ID_OPEN_INI, "Open .ini...");
		btn(ID_OPEN_MAP, "Start from map...");
		btn(ID_SAVE_MAP, "Save as stock map...");
		btn(ID_FIRST, "|<");
		btn(ID_PREV, "<");
		m_play = btn(ID_PLAY, "Play");
		btn(ID_NEXT, ">");
		btn(ID_LAST, ">|");
		btn(ID_EXPORT, "Export PNGs...");
		m_follow = new wxCheckBox(top, ID_FOLLOW, "follow robot");
		m_follow->SetValue(true);
		bar->Add(m_follow, 0, wxALIGN_CENTER_VERTICAL | wxALL, 4);
		m_slider = new wxSlider(top, ID_SLIDER, 0, 0, 1);
		bar->Add(m_slider, 1, wxEXPAND | wxALL, 2);
		m_stepLabel = new wxStaticText(top, wxID_ANY, "no rawlog");
		bar->Add(m_stepLabel, 0, wxALIGN_CENTER_VERTICAL | wxALL, 4);

		auto* split = new wxSplitterWindow(top, wxID_ANY, wxDefaultPosition, wxDefaultSize, wxSP_LIVE_UPDATE);
		auto* views = new wxPanel(split);
		auto* vs = new wxBoxSizer(wxVERTICAL);
		auto* row1 = new wxBoxSizer(wxHORIZONTAL);
		auto addCanvas = [&](wxSizer* s, View v, const char* title, int prop) {
			auto* box = new wxStaticBoxSizer(wxVERTICAL, views, title);
			auto* c = new ViewCanvas(box->GetStaticBox(), v);
			box->Add(c, 1, wxEXPAND);
			s->Add(box, prop, wxEXPAND | wxALL, 2);
			m_canvases.push_back(c);
		};
		addCanvas(
			row1, View::Frame3D,
			"Current frame: point cloud, 2.5D voxels (green ground, red obstacle, magenta drop), ground plane, RRT "
			"tree",
			1);
		addCanvas(row1, View::Map3D, "Accumulated: 2.5D map, point cloud, ground-aware grid below", 1);
		vs->Add(row1, 3, wxEXPAND);
		auto* row2 = new wxBoxSizer(wxHORIZONTAL);
		addCanvas(
			row2, View::Grids, "Grids: ground-aware | height-band | octomap (white free, black occupied, blue unknown)",
			3);
		m_status =
			new wxTextCtrl(views, wxID_ANY, "", wxDefaultPosition, wxDefaultSize, wxTE_MULTILINE | wxTE_READONLY);
		m_status->SetFont(wxFont(9, wxFONTFAMILY_TELETYPE, wxFONTSTYLE_NORMAL, wxFONTWEIGHT_NORMAL));
		row2->Add(m_status, 2, wxEXPAND | wxALL, 2);
		vs->Add(row2, 2, wxEXPAND);
		views->SetSizer(vs);

		m_props = new wxPropertyGrid(
			split, wxID_ANY, wxDefaultPosition, wxDefaultSize, wxPG_SPLITTER_AUTO_CENTER | wxPG_DEFAULT_STYLE);
		split->SplitVertically(views, m_props, -330);
		split->SetSashGravity(1.0);

		auto* main = new wxBoxSizer(wxVERTICAL);
		main->Add(bar, 0, wxEXPAND);
		main->Add(split, 1, wxEXPAND);
		top->SetSizer(main);

		Bind(
			wxEVT_BUTTON, [this](wxCommandEvent&) { onOpen(); }, ID_OPEN);
		Bind(
			wxEVT_BUTTON, [this](wxCommandEvent&) { onOpenIni(); }, ID_OPEN_INI);
		Bind(
			wxEVT_BUTTON, [this](wxCommandEvent&) { onOpenMap(); }, ID_OPEN_MAP);
		Bind(
			wxEVT_BUTTON, [this](wxCommandEvent&) { onSaveMap(); }, ID_SAVE_MAP);
		Bind(
			wxEVT_BUTTON, [this](wxCommandEvent&) { go(0); }, ID_FIRST);
		Bind(
			wxEVT_BUTTON, [this](wxCommandEvent&) { go(m_model.current() - 1); }, ID_PREV);
		Bind(
			wxEVT_BUTTON, [this](wxCommandEvent&) { go(m_model.current() + 1); }, ID_NEXT);
		Bind(
			wxEVT_BUTTON, [this](wxCommandEvent&) { go(int(m_model.stepCount()) - 1); }, ID_LAST);
		Bind(
			wxEVT_BUTTON, [this](wxCommandEvent&) { togglePlay(); }, ID_PLAY);
		Bind(
			wxEVT_BUTTON, [this](wxCommandEvent&) { onExport(); }, ID_EXPORT);
		Bind(
			wxEVT_SLIDER, [this](wxCommandEvent&) { go(m_slider->GetValue()); }, ID_SLIDER);
		Bind(
			wxEVT_TIMER,
			[this](wxTimerEvent&) {
				if (!m_model.next()) togglePlay();
				refreshAll();
			},
			ID_TIMER);
		m_props->Bind(wxEVT_PG_CHANGED, &ViewerFrame::onPropChanged, this);

		try
		{
			m_model.loadConfig(a.config, a.section);
			if (!a.initialMap.empty()) m_model.loadInitialMap(a.initialMap);
			if (!a.rawlog.empty())
			{
				m_model.openRawlog(a.rawlog);
				m_model.seek(a.frame < 0 ? 0 : a.frame);
			}
		}
		catch (const std::exception& e)
		{
			wxMessageBox(e.what(), "ground-aware-viewer", wxICON_ERROR);
		}
		fillProperties();
		CallAfter([this] { refreshAll(true); });
		if (!a.guiSnapshot.empty())
		{
			// self-check: exercise a parameter edit, then grab the window (X server pixels)
			m_snapTimer.Bind(wxEVT_TIMER, [this](wxTimerEvent&) {
				if (m_snapStage++ == 0)
				{
					if (auto* p = m_props->GetPropertyByName("K"))
					{
						m_props->ChangePropertyValue(p, wxVariant(long(100)));
						std::cout << "gui: K=100 applied, " << m_model.groundAware().lastFrame().detection.nodes.size()
								  << " RRT nodes" << std::endl;
					}
					m_snapTimer.StartOnce(1500);
					return;
				}
				wxWindowDC dc(this);
				const wxSize sz = GetSize();
				wxBitmap bmp(sz.x, sz.y);
				wxMemoryDC mem(bmp);
				wxScreenDC screen;
				const wxPoint pos = GetScreenPosition();
				mem.Blit(0, 0, sz.x, sz.y, &screen, pos.x, pos.y);
				mem.SelectObject(wxNullBitmap);
				const bool ok = bmp.SaveFile(m_args.guiSnapshot, wxBITMAP_TYPE_PNG);
				std::cout << "gui: snapshot " << (ok ? "written" : "FAILED") << " " << m_args.guiSnapshot << std::endl;
				Close(true);
			});
			m_snapTimer.StartOnce(3000);
		}
	}

   private:
	using Options = mrpt::maps::CGroundAwareOccupancyGrid::TGroundAwareOptions;

	/** The panel group of a key: the stage whose parameter struct declares it. */
	static const char* groupOf(const std::string& key)
	{
		static const auto rrt = gam::maps::ini::keys<gam::RrtGpdParams>();
		static const auto ism = gam::maps::ini::keys<gam::IsmParams>();
		static const auto pipeline = gam::maps::ini::keys<gam::PipelineParams>();
		auto has = [&](const std::vector<std::string>& v) { return std::find(v.begin(), v.end(), key) != v.end(); };
		if (has(rrt)) return "RRT-GPD";
		if (has(ism)) return "Inverse sensor model";
		if (has(pipeline)) return "2.5D map";
		return "2D scans";
	}

	void fillProperties()
	{
		m_props->Clear();
		std::map<std::string, wxPGProperty*> cats;
		for (const char* c : {"RRT-GPD", "Inverse sensor model", "2.5D map", "2D scans"})
			cats[c] = m_props->Append(new wxPropertyCategory(c));
		Options::forEachParam(m_model.groundOptions(), [&](const gam::ParamInfo& info, const auto& v) {
			using T = std::decay_t<decltype(v)>;
			const wxString name(info.key);
			wxPGProperty* p = nullptr;
			if constexpr (std::is_same_v<T, bool>)
				p = new wxBoolProperty(name, name, v);
			else if constexpr (std::is_enum_v<T>)
			{
				// A choice (ism_model, rrt_variant): a drop-down of its names.
				wxArrayString labels;
				for (int i = 0; info.choices && info.choices[i]; i++) labels.Add(info.choices[i]);
				p = new wxEnumProperty(name, name, labels, wxArrayInt(), int(v));
			}
			else if constexpr (std::is_integral_v<T>)
				p = new wxIntProperty(name, name, long(v));
			else
				p = new wxFloatProperty(name, name, double(v));
			p->SetHelpString(wxString::Format("%s [%g, %g]", info.help, info.lo, info.hi));
			m_props->AppendIn(cats[groupOf(info.key)], p);
		});
		m_props->SetPropertyAttributeAll(wxPG_BOOL_USE_CHECKBOX, true);
	}

	void onPropChanged(wxPropertyGridEvent& ev)
	{
		wxPGProperty* p = ev.GetProperty();
		if (!p || p->IsCategory()) return;
		const std::string key = p->GetName().ToStdString();
		Options opts = m_model.groundOptions();
		const wxVariant value = p->GetValue();
		Options::forEachParam(opts, [&](const gam::ParamInfo& info, auto& v) {
			using T = std::decay_t<decltype(v)>;
			if (key != info.key) return;
			if constexpr (std::is_same_v<T, bool>)
				v = value.GetBool();
			else if constexpr (std::is_enum_v<T>)
				v = T(int(value.GetLong()));
			else if constexpr (std::is_integral_v<T>)
				v = T(value.GetLong());
			else
				v = T(value.GetDouble());
		});
		try
		{
			wxBusyCursor busy;
			m_model.applyGroundOptions(opts);  // validates, then re-runs the current frame
		}
		catch (const std::exception& e)
		{
			wxMessageBox(e.what(), "invalid parameter", wxICON_WARNING);
			CallAfter([this] { fillProperties(); });  // the options in use are unchanged
		}
		refreshAll();
	}

	void go(int k)
	{
		if (!m_model.stepCount()) return;
		wxBusyCursor busy;
		m_model.seek(std::clamp(k, 0, int(m_model.stepCount()) - 1));
		refreshAll();
	}

	void togglePlay()
	{
		if (m_timer.IsRunning())
		{
			m_timer.Stop();
			m_play->SetLabel("Play");
		}
		else if (m_model.stepCount())
		{
			m_timer.Start(150);
			m_play->SetLabel("Pause");
		}
	}

	void refreshAll(bool resetCameras = false)
	{
		const bool follow = m_follow->GetValue() || resetCameras;
		for (auto* c : m_canvases) c->update(m_model, follow || c->view() == View::Grids);
		m_status->SetValue(m_model.rawlogPath() + "\n" + m_model.statusText());
		m_slider->SetRange(0, std::max(1, int(m_model.stepCount()) - 1));
		m_slider->SetValue(std::max(0, m_model.current()));
		m_stepLabel->SetLabel(wxString::Format("%d / %zu", m_model.current() + 1, m_model.stepCount()));
	}

	void onOpen()
	{
		wxFileDialog dlg(
			this, "Open rawlog", "", "", "Rawlogs (*.rawlog)|*.rawlog|All files|*", wxFD_OPEN | wxFD_FILE_MUST_EXIST);
		if (dlg.ShowModal() != wxID_OK) return;
		try
		{
			wxBusyCursor busy;
			m_model.openRawlog(dlg.GetPath().ToStdString());
			m_model.seek(0);
		}
		catch (const std::exception& e)
		{
			wxMessageBox(e.what(), "cannot open rawlog", wxICON_ERROR);
		}
		refreshAll(true);
	}

	void onOpenIni()
	{
		wxFileDialog dlg(
			this, "Open map configuration", "", "", "INI files (*.ini)|*.ini|All files|*",
			wxFD_OPEN | wxFD_FILE_MUST_EXIST);
		if (dlg.ShowModal() != wxID_OK) return;
		try
		{
			wxBusyCursor busy;
			m_model.loadConfig(dlg.GetPath().ToStdString(), m_args.section);
		}
		catch (const std::exception& e)
		{
			wxMessageBox(e.what(), "bad configuration", wxICON_ERROR);
		}
		fillProperties();
		refreshAll(true);
	}

	void onOpenMap()
	{
		wxFileDialog dlg(
			this, "Start the grids from a stock map", "", "",
			"Occupancy grids (*.gridmap;*.gridmap.gz;*.yaml)|*.gridmap;*.gridmap.gz;*.yaml|All files|*",
			wxFD_OPEN | wxFD_FILE_MUST_EXIST);
		if (dlg.ShowModal() != wxID_OK) return;
		try
		{
			wxBusyCursor busy;
			m_model.loadInitialMap(dlg.GetPath().ToStdString());
		}
		catch (const std::exception& e)
		{
			wxMessageBox(e.what(), "cannot read the map", wxICON_ERROR);
		}
		refreshAll(true);
	}

	void onSaveMap()
	{
		wxFileDialog dlg(
			this, "Save the ground-aware grid as a stock COccupancyGridMap2D", "", "ground_aware.gridmap.gz",
			"MRPT grid (*.gridmap.gz)|*.gridmap.gz|ROS map_server (*.yaml)|*.yaml", wxFD_SAVE | wxFD_OVERWRITE_PROMPT);
		if (dlg.ShowModal() != wxID_OK) return;
		try
		{
			m_model.saveGroundAwareAsStockGrid(dlg.GetPath().ToStdString());
		}
		catch (const std::exception& e)
		{
			wxMessageBox(e.what(), "cannot save the map", wxICON_ERROR);
		}
	}

	void onExport()
	{
		wxDirDialog dlg(this, "Export a PNG of each view into", m_args.shotDir);
		if (dlg.ShowModal() != wxID_OK) return;
		const wxSize sz = m_canvases[0]->GetClientSize();
		try
		{
			wxBusyCursor busy;
			std::ostringstream log;
			exportViews(m_model, dlg.GetPath().ToStdString(), std::max(320, sz.x), std::max(240, sz.y), log);
			wxMessageBox("wrote\n" + log.str(), "ground-aware-viewer");
		}
		catch (const std::exception& e)
		{
			wxMessageBox(e.what(), "export failed", wxICON_ERROR);
		}
		refreshAll();
	}

	Args m_args;
	ViewerModel m_model;
	std::vector<ViewCanvas*> m_canvases;
	wxTextCtrl* m_status = nullptr;
	wxPropertyGrid* m_props = nullptr;
	wxSlider* m_slider = nullptr;
	wxStaticText* m_stepLabel = nullptr;
	wxButton* m_play = nullptr;
	wxCheckBox* m_follow = nullptr;
	wxTimer m_timer;
	wxTimer m_snapTimer;
	int m_snapStage = 0;
};

Args g_args;

class ViewerApp : public wxApp
{
   public:
	bool OnInit() override  // no wxApp::OnInit(): our own command line
	{
		wxInitAllImageHandlers();
		auto* f = new ViewerFrame(g_args);
		f->Show();
		return true;
	}
};
}  // namespace

wxIMPLEMENT_APP_NO_MAIN(ViewerApp);

int main(int argc, char** argv)
{
	mrpt::maps::registerGroundAwareMaps();
	mrpt::maps::registerBaselineMaps();
	try
	{
		TCLAP::CmdLine cmd("ground-aware-viewer", ' ', GAM_VERSION);
		TCLAP::UnlabeledValueArg<std::string> argFile("file", "rawlog", false, "", "FILE.rawlog", cmd);
		TCLAP::ValueArg<std::string> argRawlog("r", "rawlog", "rawlog to open", false, "", "FILE", cmd);
		TCLAP::ValueArg<std::string> argConfig(
			"c", "config", "map .ini (ground-aware-mapper format)", false, "", "FILE.ini", cmd);
		TCLAP::ValueArg<std::string> argSection(
			"s", "section", "section with the <map>_count keys", false, "map", "NAME", cmd);
		TCLAP::ValueArg<int> argFrame(
			"f", "frame", "depth frame (step) to show, 0-based; default: batch the last, GUI the first", false, -1, "N",
			cmd);
		TCLAP::ValueArg<std::string> argShots(
			"", "screenshot-dir", "write DIR/<view>.png of every view (with --exit: batch mode, no display)", false, "",
			"DIR", cmd);
		TCLAP::ValueArg<std::string> argInitial(
			"", "initial-map",
			"the ground-aware and height-band grids start from a stock map (.gridmap, .gridmap.gz or ROS .yaml)", false,
			"", "FILE", cmd);
		TCLAP::SwitchArg argExit("", "exit", "batch mode: render the screenshots and exit", cmd);
		TCLAP::ValueArg<int> argW("", "width", "screenshot width [px]", false, 800, "W", cmd);
		TCLAP::ValueArg<int> argH("", "height", "screenshot height [px]", false, 600, "H", cmd);
		TCLAP::ValueArg<std::string> argGuiShot(
			"", "gui-snapshot", "(self-check) open the GUI, edit K, save the window to FILE.png and quit", false, "",
			"FILE", cmd);
		if (const int rc = gam::parseCommandLine(cmd, argc, argv, "ground-aware-viewer"); rc >= 0) return rc;
		Args a;
		a.rawlog = argRawlog.isSet() ? argRawlog.getValue() : argFile.getValue();
		a.config = argConfig.getValue();
		a.section = argSection.getValue();
		a.frame = argFrame.getValue();
		a.shotDir = argShots.getValue();
		a.initialMap = argInitial.getValue();
		a.exit = argExit.getValue();
		a.width = argW.getValue();
		a.height = argH.getValue();
		a.guiSnapshot = argGuiShot.getValue();
		if (a.exit)
		{
			if (a.rawlog.empty() || a.shotDir.empty())
			{
				std::cerr << "ground-aware-viewer: error: --exit needs a rawlog and --screenshot-dir" << std::endl;
				return 2;
			}
			return runBatch(a);
		}
		g_args = a;
		char* argv0[] = {argv[0], nullptr};
		int argc0 = 1;
		return wxEntry(argc0, argv0);
	}
	catch (const TCLAP::ArgException& e)
	{
		std::cerr << "ground-aware-viewer: error: " << e.error() << " for " << e.argId() << std::endl;
		return 2;
	}
	catch (const std::exception& e)
	{
		std::cerr << "ground-aware-viewer: error: " << e.what() << std::endl;
		return 1;
	}
}
