//! The closing line over a `cargo test` run: `total: N passed, M failed`, the sum of every
//! `test result:` line (each test binary and the doc-tests print one). CI reads this line.

/// Running sums of the `test result:` lines seen so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Totals {
    pub passed: u64,
    pub failed: u64,
}

impl Totals {
    /// Adds one line of `cargo test`'s output if it is a `test result:` line, as libtest prints
    /// it: `test result: ok. 12 passed; 0 failed; 1 ignored; 0 measured; 0 filtered out; …`.
    pub fn add_line(&mut self, line: &str) {
        let Some(rest) = line.strip_prefix("test result:") else { return };
        let words: Vec<&str> = rest.split_whitespace().collect();
        let count_before = |label: &str| -> u64 {
            words
                .iter()
                .position(|w| w.trim_end_matches([';', ',']) == label)
                .and_then(|i| i.checked_sub(1))
                .and_then(|i| words[i].parse().ok())
                .unwrap_or(0)
        };
        self.passed += count_before("passed");
        self.failed += count_before("failed");
    }

    /// The closing line, without its newline.
    pub fn closing_line(&self) -> String {
        format!("total: {} passed, {} failed", self.passed, self.failed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_every_test_result_line() {
        let output = "\
running 3 tests
test a ... ok
test result: ok. 3 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out; finished in 0.01s

running 0 tests
test result: ok. 0 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out; finished in 0.00s

test b ... FAILED
test result: FAILED. 41 passed; 2 failed; 1 ignored; 0 measured; 5 filtered out; finished in 12.34s
   Doc-tests gdshader
test result: ok. 7 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out; finished in 1.00s
";
        let mut totals = Totals::default();
        output.lines().for_each(|l| totals.add_line(l));
        assert_eq!(totals, Totals { passed: 51, failed: 2 });
        assert_eq!(totals.closing_line(), "total: 51 passed, 2 failed");
    }

    #[test]
    fn ignores_other_lines() {
        let mut totals = Totals::default();
        for line in [
            "  test result: ok. 9 passed; 0 failed;",
            "note: test result: 5 passed",
            "test result:",
            "test result: ok. many passed; 1 failed;",
            "passed failed",
        ] {
            totals.add_line(line);
        }
        assert_eq!(totals, Totals { passed: 0, failed: 1 });
        assert_eq!(Totals::default().closing_line(), "total: 0 passed, 0 failed");
    }
}
