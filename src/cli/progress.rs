//! Progress on stderr, drawn only when stderr is a terminal (through indicatif): the phase under
//! way or the volumes done, with the time elapsed, the rate and the time left.
//!
//! The library only reports where it is ([`Progress`]: the phase and the fraction of it done);
//! the timing is the CLI's: elapsed from the phase's start (or the command's, for volumes), the
//! rate smoothed exponentially by indicatif (weights fading over 15 s, stalls included), and the
//! time left from that rate, shown only from 2 s and 1% of the work on. Once a store at a URL
//! has been read from, the line also says the bytes fetched (over every store, so far).

use std::fmt::Write as _;
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, LazyLock, Mutex, OnceLock};
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle};
use slabscope::{Cancel, Monitor, Progress};

/// What a bar counts: the percent of a phase, or volumes.
#[derive(Clone, Copy)]
enum Counting {
    Phases,
    Volumes,
    /// A store at a URL read: no fraction known, the time and the bytes fetched.
    Fetching,
}

/// Draws `[########............]  43% view search  12.3 s elapsed, ~16 s left` (or
/// `[########............] 5/12 volumes  1m 03s elapsed, 4.8/min, ~1m 28s left`) on stderr,
/// redrawn in place and ticking while the work stalls; nothing when stderr is not a terminal.
/// The line is cleared when the bar is dropped.
pub struct Bar {
    bar: Option<ProgressBar>,
    /// The phase shown, and the fraction of it last reported.
    phase: Mutex<(&'static str, f64)>,
}

/// Between redraws while the work stalls: five a second, enough for the tenths of the time
/// elapsed to move, and nothing beside the work.
const TICK: Duration = Duration::from_millis(200);

impl Bar {
    /// A bar for the phases of a long computation, drawn from the first progress on.
    pub fn phases() -> Self {
        Self::new(Counting::Phases, 100)
    }

    /// A bar for `total` volumes, drawn at once.
    pub fn volumes(total: usize) -> Self {
        let bar = Self::new(Counting::Volumes, total as u64);
        if let Some(b) = &bar.bar {
            b.enable_steady_tick(TICK);
        }
        bar
    }

    /// A line for reading `what` (a store at a URL), drawn at once: the time elapsed and the
    /// bytes fetched.
    pub fn fetching(what: String) -> Self {
        let bar = Self::new(Counting::Fetching, 1);
        if let Some(b) = &bar.bar {
            b.set_message(what);
            b.enable_steady_tick(TICK);
        }
        bar
    }

    fn new(counting: Counting, len: u64) -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let template = match counting {
                Counting::Phases => "[{bar:20}] {percent:>3}% {msg}  {timing}",
                Counting::Volumes => "[{bar:20}] {pos}/{len} volumes  {timing}",
                Counting::Fetching => "{msg}  {timing}",
            };
            let style = ProgressStyle::with_template(template)
                .expect("the template is valid")
                .progress_chars("##.")
                .with_key(
                    "timing",
                    move |s: &ProgressState, w: &mut dyn std::fmt::Write| {
                        let _ = w.write_str(&match counting {
                            Counting::Fetching => {
                                format!("{} elapsed", duration(s.elapsed(), true))
                            }
                            _ => timing(
                                s.elapsed(),
                                s.pos(),
                                s.len().unwrap_or(1),
                                s.per_sec(),
                                matches!(counting, Counting::Volumes),
                            ),
                        });
                        let _ = w.write_str(&fetched(slabscope::formats::remote::bytes_fetched()));
                    },
                );
            ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr()).with_style(style)
        });
        Self {
            bar,
            phase: Mutex::new(("", 0.0)),
        }
    }

    /// Redraws the bar at `progress`; a phase starting (another name, or a phase's start at
    /// exactly 0, which only `Monitor::start` reports) starts its clock afresh. Threads report
    /// as they finish, so a fraction below the last one is late, and ignored.
    pub fn set(&self, progress: Progress) {
        let Some(bar) = &self.bar else { return };
        let mut phase = self
            .phase
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if phase.0 != progress.phase || progress.fraction == 0.0 {
            if phase.0.is_empty() {
                bar.enable_steady_tick(TICK);
            }
            bar.reset();
            bar.set_message(progress.phase);
        } else if progress.fraction < phase.1 {
            return;
        }
        *phase = (progress.phase, progress.fraction);
        let units = bar.length().unwrap_or(1) as f64;
        bar.set_position((progress.fraction.clamp(0.0, 1.0) * units).round() as u64);
    }

    /// Redraws the bar with `done` volumes (or units) done.
    pub fn set_done(&self, done: usize) {
        if let Some(bar) = &self.bar {
            bar.set_position(done as u64);
        }
    }

    /// Runs `f` with the bar off the screen, so what it prints does not run into the bar.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        match &self.bar {
            Some(bar) => bar.suspend(f),
            None => f(),
        }
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// The timing after the bar: `12.3 s elapsed, ~16 s left`; with `rate`, the units done a minute
/// before the time left (`1m 03s elapsed, 4.8/min, ~1m 28s left`). The rate and the time left
/// wait for 2 s and 1% of the work, and for a rate above nothing.
fn timing(elapsed: Duration, done: u64, total: u64, per_sec: f64, rate: bool) -> String {
    let mut s = format!("{} elapsed", duration(elapsed, true));
    let settled = elapsed >= SETTLE && done as f64 >= total.max(1) as f64 * 0.01 && done > 0;
    if !(settled && per_sec.is_finite() && per_sec > 0.0) {
        return s;
    }
    if rate {
        let per_min = per_sec * 60.0;
        let _ = if per_min < 10.0 {
            write!(s, ", {per_min:.1}/min")
        } else {
            write!(s, ", {per_min:.0}/min")
        };
    }
    let left = total.saturating_sub(done) as f64 / per_sec;
    if done < total
        && let Ok(left) = Duration::try_from_secs_f64(left)
        && left < LONGEST
    {
        let _ = write!(s, ", ~{} left", duration(left, false));
    }
    s
}

/// How long before the rate and the time left mean something.
const SETTLE: Duration = Duration::from_secs(2);

/// Estimates beyond this are not shown: a stalled start, not a forecast.
const LONGEST: Duration = Duration::from_secs(100 * 3600);

/// `d` as a user reads it: `0.4 s`, `12.3 s` (whole seconds without `tenths`: `16 s`), `1m 03s`,
/// `2h 05m`.
fn duration(d: Duration, tenths: bool) -> String {
    let t = (d.as_secs_f64() * 10.0).round() as u64;
    if tenths && t < 600 {
        return format!("{}.{} s", t / 10, t % 10);
    }
    let s = d.as_secs_f64().round() as u64;
    if s < 60 {
        format!("{s} s")
    } else if s < 3600 {
        format!("{}m {:02}s", s / 60, s % 60)
    } else {
        format!("{}h {:02}m", s / 3600, s % 3600 / 60)
    }
}

/// Raised at the `--timeout`: every long computation of the command stops, its load included.
static STOP: LazyLock<Arc<AtomicBool>> = LazyLock::new(|| Arc::new(AtomicBool::new(false)));

/// The `--timeout` in force, seconds.
static TIMEOUT: OnceLock<f64> = OnceLock::new();

/// Stops the command's long computations `seconds` from now (`--timeout`): they end with
/// [`slabscope::Error::Cancelled`], which [`timed_out`] words.
pub fn stop_after(seconds: f64) {
    if TIMEOUT.set(seconds).is_ok() {
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_secs_f64(seconds));
            STOP.store(true, Ordering::Relaxed);
        });
    }
}

/// [`stop_after`] the `--timeout` given, if one was.
pub fn stop_after_given(
    timeout: &super::params::Flags<super::params::Timeout>,
) -> slabscope::Result<()> {
    if let Some(t) = timeout.given.value(&slabscope::params::table::TIMEOUT)? {
        stop_after(t);
    }
    Ok(())
}

/// The cancellation a load takes: raised at the `--timeout`, as [`with_bar`]'s monitor is.
pub fn load_cancel() -> Cancel {
    Cancel::new(Arc::clone(&STOP))
}

/// The words for a computation the `--timeout` stopped, when it did.
pub fn timed_out() -> Option<String> {
    let t = TIMEOUT.get()?;
    STOP.load(Ordering::Relaxed)
        .then(|| format!("stopped at the --timeout of {t} s"))
}

/// What the progress line adds for `bytes` fetched from remote stores: nothing when none.
fn fetched(bytes: u64) -> String {
    if bytes == 0 {
        return String::new();
    }
    format!(", {} fetched", slabscope::error::short_bytes(bytes))
}

/// Runs `work`, reading the input `path`, with a line on stderr saying so, the time and the
/// bytes fetched when `path` is a URL (a store read where it lives).
pub fn while_reading<T>(path: &std::path::Path, work: impl FnOnce() -> T) -> T {
    if !slabscope::formats::remote::is_url(path) {
        return work();
    }
    // Named as errors name it: no user name, password or query, nothing raw.
    let shown = slabscope::formats::remote::shown_text(&path.to_string_lossy());
    let _line = Bar::fetching(format!("reading {}", slabscope::error::shown(&shown)));
    work()
}

/// Runs `work` with a monitor that draws its progress in a bar on stderr and stops at the
/// `--timeout`.
pub fn with_bar<T>(work: impl FnOnce(&Monitor) -> T) -> T {
    let bar = Bar::phases();
    let report = |p: Progress| bar.set(p);
    work(&Monitor::new(Some(STOP.as_ref()), Some(&report)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn secs(s: f64) -> Duration {
        Duration::from_secs_f64(s)
    }

    #[test]
    fn bytes_fetched_are_said_once_there_are_any() {
        assert_eq!(fetched(0), "");
        assert!(fetched(3 << 20).starts_with(", 3"), "{}", fetched(3 << 20));
        assert!(fetched(3 << 20).ends_with(" fetched"));
    }

    #[test]
    fn durations_read_in_tenths_seconds_minutes_and_hours() {
        assert_eq!(duration(secs(0.0), true), "0.0 s");
        assert_eq!(duration(secs(12.34), true), "12.3 s");
        assert_eq!(duration(secs(59.94), true), "59.9 s");
        assert_eq!(duration(secs(59.96), true), "1m 00s");
        assert_eq!(duration(secs(15.6), false), "16 s");
        assert_eq!(duration(secs(59.6), false), "1m 00s");
        assert_eq!(duration(secs(63.0), true), "1m 03s");
        assert_eq!(duration(secs(3599.4), false), "59m 59s");
        assert_eq!(duration(secs(3600.0), false), "1h 00m");
        assert_eq!(duration(secs(7530.0), true), "2h 05m");
    }

    #[test]
    fn a_phase_shows_elapsed_then_the_time_left() {
        // 43% in 12.3 s, at 2.7% a second lately: 57% left takes about 21 s.
        assert_eq!(
            timing(secs(12.3), 43, 100, 2.7, false),
            "12.3 s elapsed, ~21 s left"
        );
        assert_eq!(timing(secs(12.3), 100, 100, 2.7, false), "12.3 s elapsed");
    }

    #[test]
    fn no_estimate_before_two_seconds_or_one_percent() {
        assert_eq!(timing(secs(1.9), 50, 100, 25.0, false), "1.9 s elapsed");
        assert_eq!(timing(secs(30.0), 0, 100, 0.0, false), "30.0 s elapsed");
        assert_eq!(timing(secs(30.0), 9, 1000, 0.3, true), "30.0 s elapsed");
        assert_eq!(
            timing(secs(30.0), 10, 1000, 0.3, true),
            "30.0 s elapsed, 18/min, ~55m 00s left"
        );
        // A rate of nothing, or one so slow the estimate is no forecast: elapsed alone.
        assert_eq!(timing(secs(5.0), 1, 2, 0.0, true), "5.0 s elapsed");
        assert_eq!(timing(secs(5.0), 1, 2, f64::NAN, true), "5.0 s elapsed");
        assert_eq!(
            timing(secs(5.0), 1, 2, 1e-9, true),
            "5.0 s elapsed, 0.0/min"
        );
    }

    #[test]
    fn volumes_show_their_rate_a_minute() {
        assert_eq!(
            timing(secs(63.0), 5, 12, 0.08, true),
            "1m 03s elapsed, 4.8/min, ~1m 28s left"
        );
        assert_eq!(
            timing(secs(3.0), 40, 100, 12.0, true),
            "3.0 s elapsed, 720/min, ~5 s left"
        );
    }

    #[test]
    fn off_a_terminal_nothing_is_drawn() {
        // The tests' stderr is captured, not a terminal: no bar, and setting it is harmless.
        if std::io::stderr().is_terminal() {
            return;
        }
        let bar = Bar::phases();
        assert!(bar.bar.is_none());
        bar.set(Progress {
            phase: "view search",
            fraction: 0.5,
        });
        assert_eq!(bar.suspend(|| 7), 7);
        assert!(Bar::volumes(3).bar.is_none());
    }
}
