//! Progress of the long generators (`kc-tables`, `fit-ltc`,
//! `fit-ltc-coat`) on stderr. On a terminal it is an indicatif bar.
//! Elsewhere (a log file, a pipe) a bar would print nothing useful, so it
//! is plain lines: one when the first step is done (the rate is known
//! early), then one whenever `LINE_EVERY` seconds have passed or another
//! tenth of the work is done, and one at the end:
//!
//! ```text
//! kc-tables: 1/116 tables (0 %), 0.5 s, about 57 s left
//! ```

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// Seconds between two plain progress lines at most (unless a tenth of
/// the work is done sooner).
pub(crate) const LINE_EVERY: f64 = 5.0;

/// A progress report: a bar, plain lines, or nothing.
pub struct Progress {
    kind: Kind,
}

enum Kind {
    Hidden,
    Bar(ProgressBar),
    Lines(Lines),
}

struct Lines {
    name: String,
    unit: &'static str,
    total: u64,
    done: AtomicU64,
    start: Instant,
    /// When the last line was printed, and the tenth of the work it
    /// reported.
    last: Mutex<(Instant, u64)>,
}

impl Progress {
    /// Progress of `total` steps called `unit` ("tables", "cells") by
    /// `name`: a bar when stderr is a terminal, plain lines otherwise,
    /// nothing when not `show`.
    pub fn new(name: &str, unit: &'static str, total: u64, show: bool) -> Progress {
        Self::with_terminal(name, unit, total, show, std::io::stderr().is_terminal())
    }

    /// As [`Progress::new`], with whether stderr is a terminal given.
    fn with_terminal(
        name: &str,
        unit: &'static str,
        total: u64,
        show: bool,
        terminal: bool,
    ) -> Progress {
        let kind = if !show {
            Kind::Hidden
        } else if terminal {
            let b = ProgressBar::new(total);
            b.set_style(
                ProgressStyle::with_template(&format!(
                    "{name} {{bar:40}} {{pos}}/{{len}} {unit}, {{elapsed}} (eta {{eta}})"
                ))
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            Kind::Bar(b)
        } else {
            let now = Instant::now();
            Kind::Lines(Lines {
                name: name.to_string(),
                unit,
                total,
                done: AtomicU64::new(0),
                start: now,
                last: Mutex::new((now, 0)),
            })
        };
        Progress { kind }
    }

    /// One more step done (from any thread).
    pub fn inc(&self) {
        match &self.kind {
            Kind::Hidden => {}
            Kind::Bar(b) => b.inc(1),
            Kind::Lines(l) => {
                let done = l.done.fetch_add(1, Ordering::Relaxed) + 1;
                if let Some(line) = l.line_due(done, Instant::now()) {
                    eprintln!("{line}");
                }
            }
        }
    }

    /// The work is over: the bar is completed, or a last line printed.
    pub fn finish(&self) {
        match &self.kind {
            Kind::Hidden => {}
            Kind::Bar(b) => b.finish(),
            Kind::Lines(l) => {
                eprintln!("{}", l.text(l.done.load(Ordering::Relaxed), Instant::now()))
            }
        }
    }
}

impl Lines {
    /// The line to print after step `done` at `now`, if one is due: after
    /// the first step, after [`LINE_EVERY`] seconds since the last line,
    /// or when another tenth of the work is done. Never for the last step
    /// ([`Progress::finish`] prints that one).
    fn line_due(&self, done: u64, now: Instant) -> Option<String> {
        if done >= self.total {
            return None;
        }
        let tenth = done * 10 / self.total.max(1);
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        let due =
            done == 1 || tenth > last.1 || now.duration_since(last.0).as_secs_f64() >= LINE_EVERY;
        if !due {
            return None;
        }
        *last = (now, tenth.max(last.1));
        Some(self.text(done, now))
    }

    /// `name: done/total unit (p %), t s, about r s left`.
    fn text(&self, done: u64, now: Instant) -> String {
        let t = now.duration_since(self.start).as_secs_f64();
        let mut s = format!(
            "{}: {done}/{} {} ({} %), {}",
            self.name,
            self.total,
            self.unit,
            done * 100 / self.total.max(1),
            seconds(t)
        );
        if done > 0 && done < self.total {
            let left = t / done as f64 * (self.total - done) as f64;
            s += &format!(", about {} left", seconds(left));
        }
        s
    }
}

/// Seconds as `0.5 s`, `12 s`.
fn seconds(t: f64) -> String {
    if t < 10.0 {
        format!("{t:.1} s")
    } else {
        format!("{t:.0} s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    fn lines(total: u64) -> Lines {
        match Progress::with_terminal("fit", "cells", total, true, false).kind {
            Kind::Lines(l) => l,
            _ => panic!("not a terminal: plain lines"),
        }
    }

    /// Off a terminal: a line after the first step, at each tenth and
    /// after LINE_EVERY seconds, and none in between.
    #[test]
    fn plain_lines_come_first_at_each_tenth_and_every_few_seconds() {
        let l = lines(100);
        let t0 = l.start;
        let ms = |m: u64| t0 + Duration::from_millis(m);
        assert_eq!(
            l.line_due(1, ms(10)).as_deref(),
            Some("fit: 1/100 cells (1 %), 0.0 s, about 1.0 s left")
        );
        assert_eq!(l.line_due(2, ms(20)), None);
        assert_eq!(l.line_due(9, ms(90)), None);
        let at_tenth = l.line_due(10, ms(100)).expect("a tenth done");
        assert!(
            at_tenth.starts_with("fit: 10/100 cells (10 %)"),
            "{at_tenth}"
        );
        assert_eq!(l.line_due(11, ms(4000)), None);
        let late = l
            .line_due(12, ms(5200))
            .expect("five seconds since the last");
        assert!(
            late.starts_with("fit: 12/100 cells (12 %), 5.2 s"),
            "{late}"
        );
        assert_eq!(l.line_due(13, ms(5300)), None);
        // The last step is left to finish().
        assert_eq!(l.line_due(100, ms(9000)), None);
        assert_eq!(l.text(100, ms(60_000)), "fit: 100/100 cells (100 %), 60 s");
    }

    #[test]
    fn hidden_and_terminal_print_no_lines() {
        assert!(matches!(
            Progress::with_terminal("a", "b", 3, false, false).kind,
            Kind::Hidden
        ));
        assert!(matches!(
            Progress::with_terminal("a", "b", 3, true, true).kind,
            Kind::Bar(_)
        ));
    }
}
