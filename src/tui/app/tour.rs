//! The guided tour (`slabscope tour`): the paper in sixteen short pages, each with the live panes
//! set to show what it says. Space, →, `PgDn` or `.` the next page, ←, `PgUp` or `b` the one before (as a
//! presenter's remote sends them), q quits.
//!
//! Once the views and the histories are in, each page focuses a pane, selects the best or the
//! worst viewpoint, shows a method at a slab count and opens or closes the lesson; the user may
//! then do anything, and the next page sets them again.

use slabscope::Histories;
use slabscope::explain;
use slabscope::partition::Method;

use super::{App, Pane};
use crate::tui::event::{Effect, Task};

/// What a page draws in the exploded view's place: one of the paper's figures, or a worked
/// example on tiny data before the volume's own numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Board {
    /// Fig. 1a: the viewpoint sphere, the best axis marked.
    Sphere,
    /// Fig. 1b: rays cast from a viewpoint's plane through the volume.
    Rays,
    /// The paper's ray of five samples, its blocks and `h`.
    Blocks,
    /// Two 4-bin histograms and their JS divergence.
    Js,
    /// A 2×2 joint histogram, its MI and NMI.
    Nmi,
}

/// The tour's place: the page shown, and whether the panes were set for it (they are once the
/// page's data is in).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tour {
    /// The page, from 0.
    pub page: usize,
    /// Whether the panes are set for the page.
    pub applied: bool,
    /// What the page adds from the volume's own numbers.
    pub numbers: Option<String>,
    /// Paper mode (`tour --paper`): the paper's single lattice, every voxel counted.
    pub paper: bool,
    /// On the page of a merge, until the user steps (n p, + -, m, Home End): the lesson shows
    /// the merge of the highest NMI taken to the step shown (the last one may join slabs barely
    /// alike), new histories (full resolution) included; once stepped, it follows the steps.
    pub best_merge: bool,
}

/// The numbers a page adds to its paragraph, from the histories shown at `slabs` slabs.
pub fn page_numbers(page: usize, histories: &Histories, slabs: usize) -> Option<String> {
    let kept = |method| {
        let position = position(histories, method, slabs)?;
        Some(histories.information(&histories.slabs(method, position)))
    };
    let bottom = histories.bottom();
    match page {
        COMPARED => {
            let mut text = format!(
                "Here {slabs} slabs keep {:.4} bits top-down and {:.4} bits bottom-up, of H = {:.4}.",
                kept(Method::TopDown)?,
                kept(Method::BottomUp)?,
                histories.entropy()
            );
            if let Some(b) = bottom.and_then(|h| explain::boundaries(h, slabs)) {
                text.push(' ');
                text.push_str(&explain::boundaries_brief(&b));
            }
            Some(text)
        }
        MERGE => explain::structure(bottom?)
            .filter(|s| s.at.slabs == slabs)
            .map(|s| explain::structure_brief(&s)),
        _ => None,
    }
}

/// Which viewpoint a page selects.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Row {
    /// The best.
    Best,
    /// The worst.
    Worst,
}

/// What a page sets the panes to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Setup {
    /// The pane focused.
    pub focus: Pane,
    /// Whether the lesson shows.
    pub lesson: bool,
    /// The viewpoint selected.
    pub row: Row,
    /// The method shown.
    pub method: Method,
    /// The slab count shown.
    pub slabs: usize,
}

/// One page: its title, its paragraph, and what the panes show.
pub struct Page {
    /// The title.
    pub title: &'static str,
    /// The paragraph (the paper's equation in plain text).
    pub text: &'static str,
    /// The panes.
    pub setup: Setup,
    /// What shows in the exploded view's place, if anything.
    pub board: Option<Board>,
}

const fn setup(focus: Pane, lesson: bool, row: Row, method: Method, slabs: usize) -> Setup {
    Setup {
        focus,
        lesson,
        row,
        method,
        slabs,
    }
}

/// The slab count of the pages that show the analysis's partition: the library's default, or
/// what `--slabs K` (or `--threshold T`) gives, as in an export of the same analysis. Pages that
/// show one slab or the first split keep theirs.
pub const SHOWN: usize = 4;

/// The slab count of the pages on bottom-up's merges: where the history shows structure
/// ([`explain::structure`], computed from the volume), or the analysis's when it has none.
pub const STRUCTURED: usize = 0;

impl Setup {
    /// The slab count the page shows when the analysis gives `given` slabs and bottom-up's
    /// history shows structure at `structured`.
    pub fn slabs_with(&self, given: usize, structured: Option<usize>) -> usize {
        match self.slabs {
            SHOWN => given,
            STRUCTURED => structured.unwrap_or(given),
            k => k,
        }
    }
}

/// The page on paper mode and the defaults, whose lesson is the two modes' numbers.
pub const MODES: usize = 6;

/// The page of a merge, whose lesson is the merge of the highest NMI taken to the step shown
/// (below 1, which is a joint histogram of one cell's: `explain::example_merge`).
pub const MERGE: usize = 12;

/// The page setting top-down beside bottom-up, which adds what each keeps.
pub const COMPARED: usize = 13;

/// The tour's pages, in order.
pub const PAGES: [Page; 16] = [
    Page {
        title: "The volume and the question",
        text: "Along which direction is this volume most structured, and how should it be cut \
               into slabs across that direction so that each slab holds alike content? The \
               answer is drawn on the right: the slabs pulled apart, an exploded view \
               (Ruiz et al., Similarity-based exploded views, 2008).",
        board: None,
        setup: setup(Pane::Preview, false, Row::Best, Method::TopDown, SHOWN),
    },
    Page {
        title: "The viewpoint sphere",
        text: "The candidate directions are the vertices of a subdivided icosahedron, drawn on \
               the right as the paper's Fig. 1a: 42 viewpoints, an axis and its opposite one \
               (21 axes), the best axis marked. The list ranks them by their entropy rate, \
               lowest first.",
        board: Some(Board::Sphere),
        setup: setup(Pane::Views, false, Row::Best, Method::TopDown, SHOWN),
    },
    Page {
        title: "One ray and its samples",
        text: "Along an axis, parallel rays are cast from a plane at the viewpoint through the \
               volume, one voxel apart (the paper's lattice); each samples it one voxel apart, \
               and every sample is quantized to one of B bins. The paper's Fig. 1b on the \
               right: the plane, its rays, the volume's box and the samples of one ray.",
        board: Some(Board::Rays),
        setup: setup(Pane::Views, false, Row::Best, Method::TopDown, SHOWN),
    },
    Page {
        title: "A worked example: blocks along one ray",
        text: "The paper's example: five samples x0 … x4 on one ray form three blocks of 3 and \
               four of 2. Their frequencies give H(X^3) and H(X^2), and h = H(X^3) - H(X^2) \
               (eq. 2, 4): how much a sample still surprises once the two before it are known. \
               The numbers on the right are the library's own.",
        board: Some(Board::Blocks),
        setup: setup(Pane::Views, false, Row::Best, Method::TopDown, SHOWN),
    },
    Page {
        title: "Blocks and H(X^L)",
        text: "A block is L samples in a row on one ray. Counted over every ray, blocks have a \
               distribution p; its entropy is H(X^L) = -Σ p(x1..xL) log2 p(x1..xL) bits \
               (eq. 2). The strip is the ray through the centre, grey by bin; the lesson lists \
               the most frequent blocks and H(X^1) … H(X^L).",
        board: None,
        setup: setup(Pane::Views, true, Row::Best, Method::TopDown, SHOWN),
    },
    Page {
        title: "The entropy rate of the best and the worst axis",
        text: "h = H(X^L) - H(X^(L-1)) (eq. 4) is what is left uncertain about a sample once \
               the L-1 before it are known. The most structured view has the lowest h: here \
               the worst axis is selected, beside the best.",
        board: None,
        setup: setup(Pane::Views, true, Row::Worst, Method::TopDown, SHOWN),
    },
    Page {
        title: "The paper and this tool's defaults",
        text: "By default this tool ranks axes by the mean h over 8 shifted lattices (one \
               lattice favours the axes it lines up with) and leaves the background connected \
               to the border out of the slabs (air makes every slab alike). tour --paper \
               follows the paper: one lattice, every voxel.",
        board: None,
        setup: setup(Pane::Views, true, Row::Best, Method::TopDown, SHOWN),
    },
    Page {
        title: "Slicing along the best axis",
        text: "Across the best axis the volume is cut into slices; each slice's histogram of \
               bins is all the partition needs. The curves: the NMI of each slice with the \
               next, and the gain of one cut of the whole stack at each slice.",
        board: None,
        setup: setup(Pane::Curves, false, Row::Best, Method::TopDown, 1),
    },
    Page {
        title: "A worked example: the divergence of two histograms",
        text: "Before the volume's slabs, two of eight voxels each over four bins. JS = \
               H(p1 + p2) - π1 H(p1) - π2 H(p2) (eq. 5) is 0 when the histograms are alike and \
               grows as they differ; weighted by the parts' share of the volume it is the \
               information a cut between them gains, ΔI (eq. 6).",
        board: Some(Board::Js),
        setup: setup(Pane::Curves, false, Row::Best, Method::TopDown, 1),
    },
    Page {
        title: "The first split",
        text: "Top-down splitting takes the cut that keeps the most information: ΔI = (v1 + v2) \
               / vT · JS, with JS = H(p1 + p2) - π1 H(p1) - π2 H(p2), the Jensen-Shannon \
               divergence of the two parts' histograms (eq. 5, 6).",
        board: None,
        setup: setup(Pane::Slabs, true, Row::Best, Method::TopDown, 2),
    },
    Page {
        title: "Further splits and the gain curve",
        text: "Each step takes the best cut over all slabs, so I(slab; value), the information \
               the slabs keep about the values, grows with every split. n and p step through \
               the history; + and - change the slab count.",
        board: None,
        setup: setup(Pane::Curves, false, Row::Best, Method::TopDown, SHOWN),
    },
    Page {
        title: "A worked example: how alike two slices are",
        text: "Two slices' pixels counted by their bins in one slice and the other make a joint \
               histogram. MI = H(X) + H(Y) - H(X,Y) (eq. 7) is what one slice tells of the \
               other; NMI = MI / H(X,Y) (eq. 8) scales it to 0 … 1. Here the slices agree on \
               six pixels of eight.",
        board: Some(Board::Nmi),
        setup: setup(Pane::Slabs, false, Row::Best, Method::BottomUp, STRUCTURED),
    },
    Page {
        title: "A merge",
        text: "Bottom-up merging starts from single slices and joins the two neighbours most \
               alike: the largest NMI = MI / H(X,Y) of their joint histogram over corresponding \
               pixels, MI = H(X) + H(Y) - H(X,Y) (eq. 7, 8).",
        board: None,
        setup: setup(Pane::Slabs, true, Row::Best, Method::BottomUp, STRUCTURED),
    },
    Page {
        title: "Top-down against bottom-up",
        text: "Top-down keeps the most information about the values, bottom-up keeps alike \
               slices together; m switches the method.",
        board: None,
        setup: setup(Pane::Slabs, false, Row::Best, Method::BottomUp, SHOWN),
    },
    Page {
        title: "The optimum",
        text: "Dynamic programming over every placement of the boundaries finds the partition \
               that keeps the most information for a slab count. Greedy top-down is usually \
               within a few per cent of it; the lesson says by how much and where they differ.",
        board: None,
        setup: setup(Pane::Slabs, true, Row::Best, Method::Optimal, SHOWN),
    },
    Page {
        title: "The exploded view",
        text: "Finally the slabs are drawn pulled apart along the axis, the gaps by how unlike \
               neighbouring slabs are. Orbit with [ ] { }, change the look with r f c; q ends \
               the tour.",
        board: None,
        setup: setup(Pane::Preview, false, Row::Best, Method::TopDown, SHOWN),
    },
];

impl Tour {
    /// The first page, in paper mode when `paper`.
    pub fn new(paper: bool) -> Self {
        Self {
            page: 0,
            applied: false,
            numbers: None,
            paper,
            best_merge: false,
        }
    }

    /// The mode, as the title shows it.
    pub fn mode(&self) -> &'static str {
        if self.paper { "paper mode" } else { "defaults" }
    }

    /// Turns `by` pages, within the tour.
    pub fn turn(&mut self, by: isize) {
        let page = self.page.saturating_add_signed(by).min(PAGES.len() - 1);
        if page != self.page {
            self.page = page;
            (self.applied, self.numbers, self.best_merge) = (false, None, false);
        }
    }

    /// The page shown.
    pub fn current(&self) -> &'static Page {
        &PAGES[self.page]
    }

    /// `page 3 of 12`.
    pub fn counter(&self) -> String {
        format!("page {} of {}", self.page + 1, PAGES.len())
    }
}

/// The position of `method`'s history with `slabs` slabs, where the histories have it.
pub fn position(histories: &Histories, method: Method, slabs: usize) -> Option<usize> {
    histories
        .has(method)
        .then(|| histories.position_for(method, slabs))
}

impl App {
    /// Starts the tour at its first page, in paper mode when `paper`. The status line is the
    /// page's from now on: the terminal's note (how to let images through tmux) goes at once,
    /// not once the first page's data is in.
    pub fn start_tour(&mut self, paper: bool) {
        self.tour = Some(Tour::new(paper));
        self.status.notice = None;
    }

    /// Whether the exploded view shows large, over the four panes: on the tour's last page,
    /// unless the lesson or the help covers it.
    pub fn preview_large(&self) -> bool {
        self.tour
            .as_ref()
            .is_some_and(|t| t.page + 1 == PAGES.len())
            && !self.lesson.open
            && !self.help
    }

    /// When `action` steps (n p, + -, m, Home End), the merge page's lesson follows the steps
    /// from now on.
    pub(super) fn leave_best_merge(&mut self, action: &crate::tui::event::Action) {
        use crate::tui::event::Action;
        let steps = matches!(
            action,
            Action::Step(_) | Action::StepTo(_) | Action::Slabs(_) | Action::CycleMethod
        );
        if let Some(t) = self.tour.as_mut().filter(|_| steps) {
            t.best_merge = false;
        }
    }

    /// Turns the tour's page.
    pub(super) fn turn_page(&mut self, by: isize) -> Vec<Effect> {
        if let Some(t) = self.tour.as_mut() {
            t.turn(by);
        }
        // A message belongs to the page it was said on.
        self.status.message = None;
        self.sync_focus();
        vec![]
    }

    /// Sets the panes for the tour's page when it has not been and its data is in.
    pub(super) fn sync_tour(&mut self) -> Vec<Effect> {
        let Some(t) = self.tour.clone().filter(|t| !t.applied) else {
            return vec![];
        };
        let (Some(views), Some(h)) = (self.views.views.ready(), self.part.ready().cloned()) else {
            return vec![];
        };
        let h = h.as_ref();
        let s = t.current().setup;
        let given = match self.params.stop {
            slabscope::Stop::Slabs(k) => k,
            slabscope::Stop::Threshold(v) => h.slab_count(
                Method::TopDown,
                h.position_for_threshold(Method::TopDown, v),
            ),
        };
        let structured = h.bottom().and_then(explain::structure).map(|s| s.at.slabs);
        let s = Setup {
            slabs: s.slabs_with(given, structured),
            ..s
        };
        let numbers = page_numbers(t.page, h, s.slabs);
        let worst = views
            .views
            .iter()
            .rposition(slabscope::view::AxisEntropy::measured)
            .unwrap_or(0);
        // The optimum is not computed for a very long stack: the page shows top-down then.
        let (method, position) = match position(h, s.method, s.slabs) {
            Some(p) => (s.method, p),
            None => (
                slabscope::partition::Method::TopDown,
                h.position_for(slabscope::partition::Method::TopDown, s.slabs),
            ),
        };
        self.views.row = match s.row {
            Row::Best => 0,
            Row::Worst => worst,
        };
        self.focus = s.focus;
        (self.part.method, self.part.position) = (method, position);
        self.part.set_threshold(None);
        if self.lesson.open != s.lesson {
            self.lesson.open = s.lesson;
            (self.lesson.subject, self.lesson.lesson) = (None, Task::Idle);
        }
        self.ray = (0, 0);
        let best_merge = t.page == MERGE && method == Method::BottomUp;
        if let Some(t) = self.tour.as_mut() {
            (t.applied, t.numbers, t.best_merge) = (true, numbers, best_merge);
        }
        self.sync_focus();
        self.after_step()
    }
}
