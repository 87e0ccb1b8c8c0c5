//! The report of a traced render: which places in the source made each pixel's first NaN or
//! Inf, with pixel counts (`gdsky render --trace-nonfinite`, `gdsky stress`).

use super::Traced;

/// The colours of the places in the PNG, most pixels first (names for the report); places past
/// the last share its colour.
pub const PLACE_COLOURS: [(&str, [u8; 3]); 6] = [
    ("magenta", [255, 0, 255]),
    ("cyan", [0, 255, 255]),
    ("yellow", [255, 255, 0]),
    ("orange", [255, 128, 0]),
    ("green", [0, 200, 0]),
    ("white", [255, 255, 255]),
];

/// The places where a NaN or an infinity first appeared, with their pixel counts, most first.
/// Sites at the same place with the same text (the components of one source expression, or
/// the steps the lowering writes for one call) are one place.
pub struct NonfiniteReport {
    /// The places, most pixels first, then by location.
    pub places: Vec<Place>,
    /// The site ids of each place.
    ids: Vec<Vec<u32>>,
    /// Pixels read.
    pub pixels: usize,
    /// Pixels whose alpha is neither 0 nor a site's id (only the instrumented module writes
    /// the alpha: a non-zero count is a harness bug).
    pub unknown: usize,
}

/// One place in the source where NaN or Inf first appeared.
pub struct Place {
    /// `file:line:col` through includes and macros.
    pub location: String,
    /// The source text there.
    pub snippet: String,
    /// What the expression computes (`division`, `sqrt`, …; several joined by commas).
    pub kind: String,
    /// The function it is in.
    pub function: String,
    /// Pixels whose first non-finite value it made.
    pub pixels: usize,
}

impl NonfiniteReport {
    /// Counts the first site of each pixel of a traced render (`pixels`' alphas).
    pub fn new(traced: &Traced, pixels: &[[f32; 4]]) -> Self {
        let mut per_site = vec![0usize; traced.sites.len()];
        let mut unknown = 0usize;
        for p in pixels {
            match traced.site_of_alpha(p[3]) {
                Some(site) => per_site[site.id as usize - 1] += 1,
                None if p[3] != 0.0 => unknown += 1,
                None => {}
            }
        }
        let mut places: Vec<Place> = Vec::new();
        let mut ids: Vec<Vec<u32>> = Vec::new();
        for (site, &count) in traced.sites.iter().zip(&per_site) {
            if count == 0 {
                continue;
            }
            let location = site.location();
            match places.iter().position(|p| p.location == location && p.snippet == site.snippet) {
                Some(i) => {
                    places[i].pixels += count;
                    ids[i].push(site.id);
                    if !places[i].kind.split(", ").any(|k| k == site.kind) {
                        places[i].kind = format!("{}, {}", places[i].kind, site.kind);
                    }
                }
                None => {
                    places.push(Place {
                        location,
                        snippet: site.snippet.clone(),
                        kind: site.kind.clone(),
                        function: site.function.clone(),
                        pixels: count,
                    });
                    ids.push(vec![site.id]);
                }
            }
        }
        let mut order: Vec<usize> = (0..places.len()).collect();
        order.sort_by(|&a, &b| places[b].pixels.cmp(&places[a].pixels).then(a.cmp(&b)));
        let mut sorted_places = Vec::with_capacity(places.len());
        let mut sorted_ids = Vec::with_capacity(places.len());
        let mut places: Vec<Option<Place>> = places.into_iter().map(Some).collect();
        for i in order {
            if let Some(p) = places[i].take() {
                sorted_places.push(p);
                sorted_ids.push(std::mem::take(&mut ids[i]));
            }
        }
        NonfiniteReport { places: sorted_places, ids: sorted_ids, pixels: pixels.len(), unknown }
    }

    /// The index of the place whose site an alpha value names.
    pub fn place_of(&self, traced: &Traced, alpha: f32) -> Option<usize> {
        let id = traced.site_of_alpha(alpha)?.id;
        self.ids.iter().position(|ids| ids.contains(&id))
    }

    /// The printed report: `no NaN or Inf`, or a header and one line per place.
    pub fn text(&self) -> String {
        if self.places.is_empty() {
            return "no NaN or Inf\n".to_string();
        }
        let total: usize = self.places.iter().map(|p| p.pixels).sum();
        let mut s =
            format!("NaN or Inf first made in {total} of {} pixels, at {} place(s):\n", self.pixels, self.places.len());
        for (i, p) in self.places.iter().enumerate() {
            let colour = PLACE_COLOURS[i.min(PLACE_COLOURS.len() - 1)].0;
            s += &format!(
                "  {}: `{}` ({} in {}): {} pixels ({colour})\n",
                p.location, p.snippet, p.kind, p.function, p.pixels
            );
        }
        s
    }
}
