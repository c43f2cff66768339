//! A folder in the TUI: its pane below the others (never over the picture), filled by triage,
//! its volumes opened from it, its keys (order, filters, finding, marks and their manifest), and
//! background triage held while the open volume's work runs.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use slabscope::AnalysisParams;
use slabscope::triage::{Entry, TriageRow};

use super::{PLAIN, feed, fixture, rendered, screens};
use crate::tui::app::{App, Pane, Screen};
use crate::tui::event::{Action, Ask, Effect, FolderKey, JobMsg, Written};
use crate::tui::panes::files::Column;

fn entries(root: &Path, names: &[&str]) -> Vec<Entry> {
    names.iter().map(|n| Entry::file(root.join(n))).collect()
}

fn folder_app(root: &Path, names: &[&str]) -> (App, Vec<Effect>) {
    let screen = Screen {
        theme: PLAIN,
        ..Screen::default()
    };
    App::for_folder(
        root.to_path_buf(),
        entries(root, names),
        AnalysisParams::default(),
        screen,
    )
}

/// A row triage found: format, dims, best axis along z (uncertain or not), four slabs.
fn looked(path: &str, format: &str, dims: [usize; 3], uncertain: bool) -> TriageRow {
    let mut row = TriageRow::failed(path, String::new());
    row.error = None;
    row.format = Some(format.into());
    row.dims = Some(dims);
    row.best_axis = Some([0.0, 0.0, 1.0]);
    row.uncertain = Some(uncertain);
    row.slabs = Some(vec![[0, 10], [10, 20], [20, 30], [30, dims[2]]]);
    row
}

const NAMES: [&str; 6] = [
    "a_head.nii",
    "b_knee.nrrd",
    "c_broken.nii",
    "d_chest.mha",
    "e_body.nrrd",
    "f_waiting.nii",
];

/// A folder of six whose first volume has loaded, been searched and partitioned, and drawn;
/// triage has filled five rows (one failed, one uncertain, one with a problem).
fn filled(w: u16, h: u16) -> App {
    let root = Path::new("/data");
    let (mut app, _) = folder_app(root, &NAMES);
    let (volume, views, histories) = fixture();
    feed(&mut app, volume, views, histories);
    let cells = crate::tui::ui::preview_cells(
        ratatui::layout::Rect::new(0, 0, w, h),
        false,
        Some(NAMES.len()),
        false,
    )
    .unwrap();
    app.update(Action::PreviewArea(cells.0, cells.1));
    let generation = app.preview.generation;
    let image = rendered(cells.0, cells.1);
    app.update(Action::Job(JobMsg::Rendered(
        generation,
        Ok(Box::new(image)),
    )));
    let mut knee = looked("/data/b_knee.nrrd", "NRRD", [128, 128, 60], true);
    knee.problems = vec!["the file states no orientation".into()];
    let rows = [
        looked("/data/a_head.nii", "NIfTI", [24, 24, 40], false),
        knee,
        TriageRow::failed(
            "/data/c_broken.nii",
            "the name says NIfTI, but the header is 12 bytes long: a NIfTI-1 header is 348 \
             bytes (a truncated or mislabelled file)"
                .into(),
        ),
        looked("/data/d_chest.mha", "MetaImage", [256, 256, 120], false),
        looked("/data/e_body.nrrd", "NRRD", [64, 64, 80], false),
    ];
    for (i, row) in rows.into_iter().enumerate() {
        app.update(Action::Job(JobMsg::Triaged(i, Box::new(row))));
    }
    app
}

#[test]
fn the_pane_shows_below_the_picture_at_80x24_and_160x48() {
    for (w, h, name) in [(80, 24, "folder_80x24"), (160, 48, "folder_160x48")] {
        let mut app = filled(w, h);
        let shots = screens(&mut app, w, h, vec![]);
        insta::assert_snapshot!(name, shots[0]);
        let areas = crate::tui::ui::areas(
            ratatui::layout::Rect::new(0, 0, w, h),
            false,
            Some(NAMES.len()),
        )
        .unwrap();
        assert!(
            areas.files.intersection(areas.preview).is_empty() && areas.files.height >= 5,
            "{areas:?}"
        );
        assert!(!app.preview.covered, "nothing covers the picture");
    }
    // The smallest screen the panes take: the picture keeps rows beside the folder's pane.
    let small = ratatui::layout::Rect::new(0, 0, 60, 18);
    let a = crate::tui::ui::areas(small, false, Some(NAMES.len())).unwrap();
    assert_eq!((a.files.height, a.preview.height), (5, 6), "{a:?}");
    screens(&mut filled(60, 18), 60, 18, vec![]);
    // The failed row's error in full under the table, once the cursor is on it.
    let mut app = filled(160, 48);
    app.update(Action::Move(2));
    let shot = screens(&mut app, 160, 48, vec![]).remove(0);
    insta::assert_snapshot!("folder_160x48_error", shot);
    assert!(shot.contains("(a truncated or mislabelled file)"), "{shot}");
}

#[test]
fn a_folder_opens_as_a_pane_whose_volumes_open_in_turn() {
    let root = PathBuf::from("/data");
    let paths = entries(&root, &["a.nii", "b.nrrd", "c.mha"]);
    let (mut app, effects) = folder_app(&root, &["a.nii", "b.nrrd", "c.mha"]);
    assert!(
        matches!(&effects[..], [Effect::Load, Effect::PauseTriage(true), Effect::Triage(p, _)] if p == &paths),
        "{effects:?}"
    );
    let files = app.files.as_ref().unwrap();
    assert!(files.shown && files.open == 0 && files.name(1) == "b.nrrd");
    assert_eq!(app.focus, Pane::Files, "the folder's pane has the keys");
    // Rows fill in as triage completes them.
    let row = TriageRow::failed("/data/c.mha", "broken".into());
    app.update(Action::Job(JobMsg::Triaged(2, Box::new(row))));
    assert!(app.files.as_ref().unwrap().rows[2].is_some());
    // The cursor moves in the pane; Enter opens its volume, afresh, the pane keeping the keys.
    app.update(Action::Move(1));
    let effects = app.update(Action::Select);
    assert!(
        matches!(&effects[..], [Effect::Cancel, Effect::Open(p), Effect::Load] if p == &paths[1]),
        "{effects:?}"
    );
    let files = app.files.as_ref().unwrap();
    assert!(files.shown && files.open == 1 && app.focus == Pane::Files);
    assert!(files.rows[2].is_some(), "the pane keeps its rows");
    assert_eq!(app.name, "/data/b.nrrd");
    // Page down and up step through the volumes, and stop at the ends.
    let effects = app.update(Action::Page(1));
    assert!(
        matches!(&effects[..], [Effect::Cancel, Effect::Open(p), Effect::Load] if p == &paths[2]),
        "{effects:?}"
    );
    assert!(app.update(Action::Page(1)).is_empty(), "the last volume");
    app.update(Action::Page(-1));
    assert_eq!(app.files.as_ref().unwrap().open, 1);
    // F hides the pane (the focus leaves it) and shows it again; Tab reaches it only shown.
    app.update(Action::ToggleFiles);
    assert!(!app.files.as_ref().unwrap().shown && app.focus == Pane::Views);
    for _ in 0..4 {
        app.update(Action::Focus(1));
        assert_ne!(app.focus, Pane::Files);
    }
    app.update(Action::ToggleFiles);
    app.update(Action::Focus(-1));
    assert_eq!(app.focus, Pane::Files, "before the viewpoints");
}

#[test]
fn triage_is_held_while_the_open_volume_works_and_goes_on_after() {
    let mut app = filled(100, 30);
    assert!(!app.busy(), "loaded, searched, partitioned and drawn");
    // The picture came last: the effect that let triage go on came with it.
    let root = Path::new("/data");
    let (mut fresh, _) = folder_app(root, &NAMES);
    let (volume, views, histories) = fixture();
    let mut seen = vec![];
    for msg in [
        JobMsg::Loaded(Ok((Arc::clone(volume), vec![]))),
        JobMsg::Views(0, Ok(Box::new(views.clone()))),
        JobMsg::Analysis(1, 0, Ok(Arc::clone(histories))),
    ] {
        let effects = fresh.update(Action::Job(msg));
        seen.push(
            effects
                .iter()
                .filter(|e| matches!(e, Effect::PauseTriage(_)))
                .count(),
        );
    }
    assert_eq!(
        seen,
        [0, 0, 1],
        "let go once the histories are in (no picture asked)"
    );
    // Another volume opened: held again until its work is done; Esc lets triage go on.
    let effects = app.update(Action::Page(1));
    assert!(
        effects
            .iter()
            .any(|e| matches!(e, Effect::PauseTriage(true))),
        "{effects:?}"
    );
    let effects = app.update(Action::Job(JobMsg::Loaded(Ok((
        Arc::clone(volume),
        vec![],
    )))));
    assert!(
        !effects.iter().any(|e| matches!(e, Effect::PauseTriage(_))),
        "still held"
    );
    let effects = app.update(Action::Escape);
    assert!(
        effects
            .iter()
            .any(|e| matches!(e, Effect::PauseTriage(false))),
        "{effects:?}"
    );
}

#[test]
fn the_pane_sorts_filters_and_finds() {
    let mut app = filled(100, 30);
    let order = |app: &App| app.files.as_ref().unwrap().order().to_vec();
    assert_eq!(order(&app), [0, 1, 2, 3, 4, 5]);
    app.update(Action::Folder(FolderKey::Sort));
    assert_eq!(app.files.as_ref().unwrap().sort, (Column::Status, false));
    assert_eq!(
        order(&app),
        [2, 0, 1, 3, 4, 5],
        "errors first, waiting last"
    );
    app.update(Action::Folder(FolderKey::Sort));
    app.update(Action::Folder(FolderKey::Sort));
    assert_eq!(app.files.as_ref().unwrap().sort, (Column::Dims, false));
    assert_eq!(
        order(&app),
        [0, 4, 1, 3, 2, 5],
        "fewest voxels first, unknown last"
    );
    app.update(Action::Folder(FolderKey::Reverse));
    assert_eq!(
        order(&app),
        [3, 1, 4, 0, 2, 5],
        "the waiting row stays last"
    );
    app.update(Action::Folder(FolderKey::Errors));
    assert_eq!(order(&app), [2]);
    assert_eq!(
        app.files.as_ref().unwrap().row,
        2,
        "the cursor goes to a row shown"
    );
    app.update(Action::Folder(FolderKey::Errors));
    app.update(Action::Folder(FolderKey::Uncertain));
    assert_eq!(order(&app), [1]);
    app.update(Action::Folder(FolderKey::Uncertain));
    let formats: Vec<Vec<usize>> = (0..4)
        .map(|_| {
            app.update(Action::Folder(FolderKey::Format));
            order(&app)
        })
        .collect();
    assert_eq!(
        formats,
        [vec![3], vec![0], vec![1, 4], vec![3, 1, 4, 0, 2, 5]]
    );
    // `/` finds by name as it is typed, from the cursor on.
    app.update(Action::Ask(Ask::Find));
    for c in "CHE".chars() {
        app.update(Action::Type(c));
    }
    assert_eq!(app.files.as_ref().unwrap().row, 3);
    app.update(Action::Submit);
    app.update(Action::Ask(Ask::Find));
    app.update(Action::Type('q'));
    app.update(Action::Submit);
    assert_eq!(
        app.status.message.as_deref(),
        Some("no volume's name holds \"q\"")
    );
    assert_eq!(app.files.as_ref().unwrap().row, 3, "the cursor stays");
}

#[test]
fn marks_become_a_manifest_that_reads_back_to_the_same_volumes() {
    let dir = tempfile::tempdir().unwrap();
    let names = ["a.nii", "b.nrrd", "c.mha", "d dir/e\tf.nii"];
    let (mut app, _) = folder_app(dir.path(), &names);
    let effects = app.update(Action::Ask(Ask::Manifest));
    assert!(effects.is_empty() && app.status.prompt.is_none());
    assert_eq!(
        app.status.message.as_deref(),
        Some("no volume is marked: Space marks the one under the cursor")
    );
    // Space marks and steps down: the first, (not the second), the third; the fourth.
    for key in [
        Action::Folder(FolderKey::Mark),
        Action::Move(1),
        Action::Folder(FolderKey::Mark),
        Action::Folder(FolderKey::Mark),
    ] {
        app.update(key);
    }
    let marked = app.files.as_ref().unwrap().marked.clone();
    assert_eq!(marked.into_iter().collect::<Vec<_>>(), [0, 2, 3]);
    app.update(Action::Ask(Ask::Manifest));
    let prompt = app.status.prompt.as_mut().unwrap();
    assert_eq!(prompt.text, "slabscope-marked.txt");
    let target = dir.path().join("marked.txt");
    prompt.text = target.display().to_string();
    let Some(Effect::WriteManifest(path, volumes, false)) =
        app.update(Action::Submit).into_iter().next()
    else {
        panic!("no manifest written");
    };
    let expected: Vec<Entry> = [0, 2, 3]
        .map(|i| app.files.as_ref().unwrap().paths[i].clone())
        .to_vec();
    assert_eq!(volumes, expected);
    // Written by the jobs' writer, read by the library's reader (the CLI's and Python's).
    let written = crate::tui::jobs::write_manifest(&path, &volumes, false);
    assert_eq!(written, Written::Done(3));
    assert_eq!(slabscope::triage::read_manifest(&target).unwrap(), expected);
    // Never over a file that exists unless the same name is given again.
    assert_eq!(
        crate::tui::jobs::write_manifest(&path, &volumes, false),
        Written::Exists
    );
    app.update(Action::Job(JobMsg::Manifest(path.clone(), Written::Exists)));
    let prompt = app.status.prompt.as_ref().unwrap();
    assert_eq!(
        (prompt.ask, prompt.text.as_str()),
        (Ask::Overwrite, &*target.display().to_string())
    );
    let effects = app.update(Action::Submit);
    assert!(
        matches!(&effects[..], [Effect::WriteManifest(p, _, true)] if *p == path),
        "{effects:?}"
    );
    // Never anything but a regular file.
    let folder = crate::tui::jobs::write_manifest(dir.path(), &volumes, true);
    assert!(
        matches!(folder, Written::Failed(ref e) if e.contains("not a regular file")),
        "{folder:?}"
    );
}

#[test]
fn the_cursors_thumbnail_shows_beside_the_table_where_there_is_room_and_colour() {
    let root = Path::new("/data");
    let (mut app, _) = folder_app(root, &NAMES);
    // Left half red, right half blue, as triage's cell would come.
    let image = image::RgbaImage::from_fn(64, 32, |x, _| {
        if x < 32 {
            image::Rgba([200, 0, 0, 255])
        } else {
            image::Rgba([0, 0, 200, 255])
        }
    });
    app.update(Action::Job(JobMsg::Thumbnail(0, Box::new(image))));
    let files = app.files.as_mut().unwrap();
    let draw = |files: &crate::tui::panes::files::FilesPane, w: u16| {
        let mut buf = ratatui::buffer::Buffer::empty(ratatui::layout::Rect::new(0, 0, w, 10));
        ratatui::widgets::Widget::render(files, buf.area, &mut buf);
        buf
    };
    // No colour: no thumbnail.
    assert!(!super::text(&draw(files, 160)).contains('▀'));
    files.theme = crate::tui::theme::Theme {
        color: true,
        contrast: false,
    };
    // Inside the border, 8 lines of table: a thumbnail 32 cells wide at the right.
    let buf = draw(files, 160);
    let red = ratatui::style::Color::Rgb(200, 0, 0);
    let blue = ratatui::style::Color::Rgb(0, 0, 200);
    for y in 1..9 {
        for x in 127..159 {
            let cell = &buf[(x, y)];
            assert_eq!(cell.symbol(), "▀", "({x}, {y})");
            // Away from the edge, where the scaling averages the two colours.
            let want = match x {
                ..141 => red,
                141..145 => continue,
                _ => blue,
            };
            assert_eq!((cell.fg, cell.bg), (want, want), "({x}, {y})");
        }
        assert_ne!(buf[(126, y)].symbol(), "▀");
    }
    // Narrow: none.
    assert!(!super::text(&draw(files, 100)).contains('▀'));
    // Another volume under the cursor: none, it has no thumbnail yet.
    files.step(1);
    assert!(!super::text(&draw(files, 160)).contains('▀'));
}

/// With an image protocol (sixel, 8×16 cells), the rows' thumbnails and the cursor's are one
/// picture beside the table: from 60 columns on the rows' column, 4 cells wide (a 2:1 picture
/// one line high); from 140 the cursor's beside it, 32 cells wide for 8 lines; none while the
/// help covers the pane.
#[test]
fn with_an_image_protocol_each_rows_thumbnail_shows_in_one_picture_beside_the_table() {
    use ratatui::buffer::{Buffer, CellDiffOption};
    use ratatui::layout::Rect;

    use crate::term::{Caps, Graphics};
    use crate::tui::panes::thumbs::Thumbs;

    let (mut app, _) = folder_app(Path::new("/data"), &NAMES);
    let image = image::RgbaImage::from_pixel(64, 32, image::Rgba([200, 0, 0, 255]));
    app.update(Action::Job(JobMsg::Thumbnail(0, Box::new(image.clone()))));
    app.update(Action::Job(JobMsg::Thumbnail(2, Box::new(image))));
    let files = app.files.as_mut().unwrap();
    let sixel = Caps {
        graphics: Graphics::Sixel,
        cell: (8, 16),
        ..Caps::blocks()
    };
    files.thumbs = Thumbs::new(&sixel);
    let draw = |files: &crate::tui::panes::files::FilesPane, w: u16| {
        let mut buf = Buffer::empty(Rect::new(0, 0, w, 10));
        ratatui::widgets::Widget::render(files, buf.area, &mut buf);
        buf
    };
    // The picture's first cell, the rest skipped; the table's text stops before it.
    let picture_at = |buf: &Buffer, x: u16, width: u16| {
        assert!(
            buf[(x, 1)].symbol().starts_with("\x1bP"),
            "a sixel at ({x}, 1)"
        );
        assert!(!buf[(x - 1, 1)].symbol().starts_with('\x1b'));
        for y in 1..9 {
            for dx in 0..width {
                if (dx, y) != (0, 1) {
                    assert_eq!(buf[(x + dx, y)].diff_option, CellDiffOption::Skip);
                }
            }
        }
    };
    picture_at(&draw(files, 100), 95, 4);
    // Wide, the cursor's volume having one: the rows' 4, a column between, the cursor's 32.
    picture_at(&draw(files, 160), 122, 37);
    // Too narrow for any.
    let buf = draw(files, 58);
    assert!((0..58).all(|x| !buf[(x, 1)].symbol().starts_with('\x1b')));
    // Covered by the help: nothing sent.
    files.covered = true;
    let buf = draw(files, 100);
    assert!(!buf[(95, 1)].symbol().starts_with('\x1b'));
}

#[test]
fn in_the_tour_a_remotes_keys_turn_pages_and_open_no_other_volume() {
    use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
    let root = PathBuf::from("/data");
    let (mut app, _) = folder_app(&root, &["a.nii", "b.nrrd"]);
    app.tour = Some(crate::tui::app::tour::Tour::new(false));
    let page = |app: &App| app.tour.as_ref().unwrap().page;
    let name = app.name.clone();
    for (code, to) in [
        (KeyCode::PageDown, 1),
        (KeyCode::Char('.'), 2),
        (KeyCode::Char('b'), 1),
        (KeyCode::PageUp, 0),
    ] {
        let key = KeyEvent::new(code, KeyModifiers::NONE);
        let action = crate::tui::keymap::action(key, false, app.tour.is_some()).unwrap();
        let effects = app.update(action);
        assert!(
            !effects
                .iter()
                .any(|e| matches!(e, Effect::Open(_) | Effect::Cancel | Effect::Load)),
            "{code:?}: {effects:?}"
        );
        assert_eq!(page(&app), to, "{code:?}");
        assert_eq!(app.files.as_ref().unwrap().open, 0, "{code:?}");
        assert_eq!(app.name, name);
    }
    // Outside the tour PgDn opens the next volume.
    app.tour = None;
    let key = KeyEvent::new(KeyCode::PageDown, KeyModifiers::NONE);
    let effects = app.update(crate::tui::keymap::action(key, false, false).unwrap());
    assert!(
        effects
            .iter()
            .any(|e| matches!(e, Effect::Open(p) if p == &Entry::file(root.join("b.nrrd")))),
        "{effects:?}"
    );
}

#[test]
fn in_the_tour_a_volume_opened_from_the_folder_brings_no_terminal_note() {
    let root = PathBuf::from("/data");
    let screen = Screen {
        theme: PLAIN,
        note: Some("tmux keeps images from the terminal".into()),
        ..Screen::default()
    };
    let names = ["a.nii", "b.nrrd"];
    let params = AnalysisParams::default();
    let (mut app, _) = App::for_folder(root.clone(), entries(&root, &names), params, screen);
    assert!(app.status.notice.is_some());
    app.start_tour(false);
    assert_eq!(app.status.notice, None);
    let open = |app: &mut App, by: isize| {
        app.focus = Pane::Files;
        app.update(Action::Move(by));
        let effects = app.update(Action::Select);
        assert!(
            effects.iter().any(|e| matches!(e, Effect::Open(_))),
            "{effects:?}"
        );
    };
    open(&mut app, 1);
    assert!(app.name.ends_with("b.nrrd"), "{}", app.name);
    assert_eq!(app.status.notice, None);
    // Outside the tour the note comes with every volume.
    app.tour = None;
    open(&mut app, -1);
    assert!(app.name.ends_with("a.nii"), "{}", app.name);
    assert!(app.status.notice.is_some());
}
