//! Godot's verdict on a shader, read from its log.
//!
//! A shader Godot's compiler rejects prints (Godot 4.6, Compatibility renderer):
//!
//! ```text
//! --Main Shader--
//!     3 | void sky() {
//! E   4->  COLOR = vec3(1.0) + 2;
//! SHADER ERROR: Invalid arguments to operator '+': 'vec3, int'.
//!    at: (null) (:4)
//! ERROR: Shader compilation failed.
//!    at: set_code (drivers/gles3/storage/material_storage.cpp:2828)
//! ```
//!
//! The line number (`(:4)`) counts the lines of the code as given, from 1.

/// One error Godot reported for a shader.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderError {
    /// The 1-based line in the shader's code, when Godot gave one.
    pub line: Option<u32>,
    /// Godot's message, without the `SHADER ERROR: ` / `ERROR: ` prefix.
    pub message: String,
}

/// Whether Godot accepted a shader, with what it said.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CompileOutcome {
    /// True when the log holds no error.
    pub accepted: bool,
    /// The errors, in log order (`SHADER ERROR` lines first-class; other `ERROR:` lines too,
    /// except the "Shader compilation failed." that follows every shader error).
    pub errors: Vec<ShaderError>,
    /// Everything Godot printed while it compiled and drew the shader.
    pub log: Vec<String>,
}

impl CompileOutcome {
    /// Reads the errors out of a job's log.
    pub fn from_log(log: Vec<String>) -> Self {
        let mut errors = Vec::new();
        let mut any_error = false;
        for (i, line) in log.iter().enumerate() {
            let next = log.get(i + 1).map(String::as_str).unwrap_or("");
            if let Some(message) = line.strip_prefix("SHADER ERROR: ") {
                any_error = true;
                errors.push(ShaderError { line: at_line(next), message: message.trim_end().to_string() });
            } else if let Some(message) = line.strip_prefix("ERROR: ") {
                any_error = true;
                if message.trim_end() != "Shader compilation failed." {
                    errors.push(ShaderError { line: None, message: message.trim_end().to_string() });
                }
            }
        }
        Self { accepted: !any_error, errors, log }
    }
}

/// The line of `   at: (null) (:4)`.
fn at_line(line: &str) -> Option<u32> {
    let rest = line.trim_start().strip_prefix("at: ")?;
    let inner = rest.trim_end().strip_suffix(')')?;
    let start = inner.rfind("(:")?;
    inner[start + 2..].parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_godots_shader_error() {
        let log: Vec<String> = [
            "--Main Shader--",
            "E   4->  COLOR = vec3(1.0) + 2;",
            "SHADER ERROR: Invalid arguments to operator '+': 'vec3, int'.",
            "   at: (null) (:4)",
            "ERROR: Shader compilation failed.",
            "   at: set_code (drivers/gles3/storage/material_storage.cpp:2828)",
        ]
        .map(String::from)
        .to_vec();
        let outcome = CompileOutcome::from_log(log);
        assert!(!outcome.accepted);
        assert_eq!(
            outcome.errors,
            [ShaderError { line: Some(4), message: "Invalid arguments to operator '+': 'vec3, int'.".into() }]
        );
        assert!(CompileOutcome::from_log(vec!["hello".into()]).accepted);
    }
}
