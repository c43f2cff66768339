//! The TUI in real graphics terminals under Xvfb: xterm (`-ti vt340`, sixel), mlterm (sixel) and
//! tmux inside xterm (sixel through the passthrough). In each, the built-in dataset's exploded
//! view shows as an image (many distinct colours in the preview pane of a screenshot), a key
//! changes it, and over 20 launches in a row the tty is in raw mode once the TUI has started
//! (`stty -a -F` shows `-icanon -echo`) and back in line mode after `q`.
//!
//! Needs `xvfb xterm mlterm tmux imagemagick xdotool` (`.ci/run` installs them). Without them the
//! test says so and passes, unless `SLABSCOPE_REQUIRE_REALTERM=1`, which makes a missing tool a
//! failure.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::binary;

const TOOLS: [&str; 6] = ["Xvfb", "xterm", "mlterm", "tmux", "import", "xdotool"];

/// Launches of the TUI in each terminal: 20 under `CI=true` (a terminal that loses the keyboard
/// one time in twenty shows there), 3 otherwise, so that the local loop stays short.
fn launches() -> usize {
    if std::env::var("CI").as_deref() == Ok("true") {
        20
    } else {
        3
    }
}

fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Whether the test can run; panics when it must run and cannot.
fn tools_present() -> bool {
    let missing: Vec<&str> = TOOLS.into_iter().filter(|t| !have(t)).collect();
    if missing.is_empty() {
        return true;
    }
    let message = format!(
        "the real-terminal test needs {} (apt-get install xvfb xterm mlterm tmux imagemagick xdotool)",
        missing.join(", ")
    );
    assert!(
        std::env::var("SLABSCOPE_REQUIRE_REALTERM").as_deref() != Ok("1"),
        "{message}"
    );
    eprintln!("SKIPPED: {message}");
    false
}

/// An X server of our own, killed when dropped.
struct Display {
    server: Child,
    name: String,
}

impl Display {
    fn start() -> Self {
        // Xvfb picks a free display and says which (stale locks of killed servers stay behind
        // and would make a display number chosen here collide).
        let mut server = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1800x1100x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb starts");
        let mut line = String::new();
        std::io::BufRead::read_line(
            &mut std::io::BufReader::new(server.stdout.take().expect("piped")),
            &mut line,
        )
        .expect("Xvfb names its display");
        let number: u32 = line.trim().parse().expect("a display number");
        let name = format!(":{number}");
        let socket = PathBuf::from(format!("/tmp/.X11-unix/X{number}"));
        wait_until(10, || socket.exists(), "the X server's socket");
        Self { server, name }
    }

    fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("DISPLAY", &self.name)
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        c
    }

    fn key(&self, key: &str) {
        let ok = self.command("xdotool").args(["key", key]).status();
        assert!(ok.is_ok_and(|s| s.success()), "xdotool key {key}");
    }

    fn screenshot(&self, path: &Path) -> image::RgbImage {
        let ok = self
            .command("import")
            .args(["-window", "root"])
            .arg(path)
            .status();
        assert!(ok.is_ok_and(|s| s.success()), "import takes a screenshot");
        image::open(path).expect("the screenshot reads").to_rgb8()
    }
}

impl Drop for Display {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

fn wait_until(secs: u64, mut done: impl FnMut() -> bool, what: &str) {
    let start = Instant::now();
    while !done() {
        assert!(
            start.elapsed() < Duration::from_secs(secs),
            "waited {secs} s for {what}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .trim()
        .to_string()
}

/// The tty's line settings, as `stty -a` prints them.
fn stty(tty: &str) -> String {
    let out = Command::new("stty")
        .args(["-a", "-F", tty])
        .output()
        .expect("stty runs");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn raw(settings: &str) -> bool {
    let words: Vec<&str> = settings.split_whitespace().collect();
    words.contains(&"-icanon") && words.contains(&"-echo")
}

fn cooked(settings: &str) -> bool {
    let words: Vec<&str> = settings.split_whitespace().collect();
    words.contains(&"icanon") && words.contains(&"echo")
}

/// The distinct colours in the preview pane of a screenshot: the terminal window is the
/// non-black part of the screen, and the preview its upper right.
fn preview_colours(shot: &image::RgbImage) -> HashSet<[u8; 3]> {
    let (mut w, mut h) = (0, 0);
    for (x, y, p) in shot.enumerate_pixels() {
        if p.0 != [0, 0, 0] {
            w = w.max(x + 1);
            h = h.max(y + 1);
        }
    }
    let mut colours = HashSet::new();
    for y in h / 20..h / 2 {
        for x in w * 45 / 100..w * 95 / 100 {
            colours.insert(shot.get_pixel(x, y).0);
        }
    }
    colours
}

/// Runs the TUI [`launches`] times in a terminal started by `terminal` (a command line that runs
/// the script it is given), checking the tty's mode around each run and the picture in the first.
fn check_terminal(display: &Display, name: &str, terminal: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let script = d.join("run.sh");
    std::fs::write(
        &script,
        format!(
            "for i in $(seq {launches}); do tty > {tty}; echo $i > {start}; {bin}; stty -a > {after}; echo $i > {end}; done; sleep 600\n",
            tty = d.join("tty").display(),
            start = d.join("start").display(),
            after = d.join("after").display(),
            end = d.join("end").display(),
            bin = binary(),
            launches = launches(),
        ),
    )
    .unwrap();
    // `SCRIPT` alone is the script's command and argument; inside a string, its command line.
    let run = format!("sh {}", script.display());
    let command: Vec<String> = terminal
        .iter()
        .flat_map(|a| match *a {
            "SCRIPT" => run.split(' ').map(String::from).collect(),
            a => vec![a.replace("SCRIPT", &run)],
        })
        .collect();
    let mut term = display
        .command(&command[0])
        .args(&command[1..])
        .spawn()
        .expect("the terminal starts");
    for i in 1..=launches() {
        let n = i.to_string();
        wait_until(
            30,
            || read(&d.join("start")) == n,
            &format!("{name}: start {i}"),
        );
        let tty = read(&d.join("tty"));
        wait_until(
            10,
            || raw(&stty(&tty)),
            &format!("{name}: raw mode after start {i}"),
        );
        if i == 1 {
            check_picture(display, name, d);
        }
        display.key("q");
        wait_until(
            20,
            || read(&d.join("end")) == n,
            &format!("{name}: quit {i}"),
        );
        // As the shell found the tty when the TUI had quit, before the next launch.
        let settings = read(&d.join("after"));
        assert!(
            cooked(&settings),
            "{name}, launch {i}: the tty is not restored after q:\n{settings}"
        );
    }
    let _ = term.kill();
    let _ = term.wait();
}

/// The preview pane shows an image, and a key changes it.
fn check_picture(display: &Display, name: &str, d: &Path) {
    let mut colours = HashSet::new();
    let start = Instant::now();
    let mut shot = image::RgbImage::new(1, 1);
    // The picture of the whole volume comes first, then the slabs; wait for a rich one.
    while colours.len() < 64 && start.elapsed() < Duration::from_secs(20) {
        std::thread::sleep(Duration::from_millis(500));
        shot = display.screenshot(&d.join("before.png"));
        colours = preview_colours(&shot);
    }
    assert!(
        colours.len() >= 64,
        "{name}: the preview shows {} colours, not an image",
        colours.len()
    );
    // Let the partition's picture settle before the key.
    std::thread::sleep(Duration::from_secs(2));
    let before = display.screenshot(&d.join("before.png"));
    display.key("bracketright");
    let mut after = before.clone();
    let start = Instant::now();
    while after == before && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(300));
        after = display.screenshot(&d.join("after.png"));
    }
    assert!(
        after != before,
        "{name}: orbiting changes nothing on screen"
    );
    assert!(preview_colours(&after).len() >= 64, "{name}: after the key");
    drop(shot);
}

const XTERM: [&str; 13] = [
    "xterm",
    "-ti",
    "vt340",
    "-xrm",
    "XTerm*decTerminalID: vt340",
    "-xrm",
    "XTerm*numColorRegisters: 256",
    "-geometry",
    "150x45+0+0",
    "-fa",
    "Monospace",
    "-fs",
    "10",
];

/// The tour in tmux inside xterm, keys typed into the xterm: it turns from its first page to its
/// last, paints the high-contrast theme's black (xterm's own background is white), and q quits
/// it with status 0.
#[test]
fn the_tour_runs_to_its_last_page_in_a_real_terminal() {
    let _alone = crate::one_at_a_time();
    if !tools_present() {
        return;
    }
    let display = Display::start();
    let dir = tempfile::tempdir().unwrap();
    let exit = dir.path().join("exit");
    let socket = format!("slabscope-tour-{}", std::process::id());
    let tour = format!(
        "{} tour --theme contrast; echo $? > {}; sleep 600",
        binary(),
        exit.display()
    );
    let tmux = format!("tmux -L {socket} -f /dev/null new-session -s tour '{tour}'");
    let mut xterm: Vec<&str> = XTERM.to_vec();
    xterm.extend(["-e", "sh", "-c", &tmux]);
    let mut term = display
        .command(xterm[0])
        .args(&xterm[1..])
        .spawn()
        .expect("xterm starts");
    let screen = || {
        let out = Command::new("tmux")
            .args(["-L", &socket, "capture-pane", "-p", "-t", "tour"])
            .output()
            .expect("tmux runs");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    wait_until(
        120,
        || screen().contains("page 1 of 16"),
        "the tour's first page",
    );
    for page in 2..=16 {
        display.key("space");
        let want = format!("page {page} of 16");
        wait_until(60, || screen().contains(&want), &want);
    }
    // Inside the xterm (at the screen's corner, 150×45 cells): dark, not xterm's white. The
    // last page's exploded view covers most of the corner, on the renderer's own near-black
    // (10, 10, 17); the panes around it are the theme's black.
    let shot = display.screenshot(&dir.path().join("tour.png"));
    let corner = image::imageops::crop_imm(&shot, 0, 0, 600, 400).to_image();
    let dark = corner
        .pixels()
        .filter(|p| p.0.iter().all(|&c| c < 48))
        .count();
    assert!(
        dark * 2 > corner.pixels().count(),
        "the contrast theme paints the terminal dark: {dark} dark pixels of {}",
        corner.pixels().count()
    );
    display.key("q");
    wait_until(30, || read(&exit) == "0", "the tour's exit status 0");
    let _ = Command::new("tmux")
        .args(["-L", &socket, "kill-server"])
        .status();
    let _ = term.kill();
    let _ = term.wait();
}

#[test]
fn the_tui_draws_images_and_keeps_the_keyboard_in_real_terminals() {
    let _alone = crate::one_at_a_time();
    if !tools_present() {
        return;
    }
    let display = Display::start();
    let mut xterm: Vec<&str> = XTERM.to_vec();
    xterm.extend(["-e", "SCRIPT"]);
    check_terminal(&display, "xterm", &xterm);
    check_terminal(
        &display,
        "mlterm",
        &["mlterm", "-g", "150x45+0+0", "-e", "SCRIPT"],
    );
    let socket = format!("slabscope-realterm-{}", std::process::id());
    let tmux = format!(
        "tmux -L {socket} -f /dev/null new-session 'tmux set -g allow-passthrough on; SCRIPT'"
    );
    let mut in_tmux: Vec<&str> = XTERM.to_vec();
    in_tmux.extend(["-e", "sh", "-c", &tmux]);
    check_terminal(&display, "tmux in xterm", &in_tmux);
    let _ = Command::new("tmux")
        .args(["-L", &socket, "kill-server"])
        .status();
}
