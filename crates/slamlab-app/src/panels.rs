//! Which panels are open around a lesson's map: shared by the shell, the layout
//! widget and the URL's `panels=` key, so it lives apart from all three.

/// Which panels are open around the map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct PanelVisibility {
    /// The parameter panel (left).
    pub parameters: bool,
    /// The explanation panel (right).
    pub explanation: bool,
    /// The plots (bottom).
    pub plots: bool,
}

impl Default for PanelVisibility {
    fn default() -> Self {
        Self {
            parameters: true,
            explanation: true,
            plots: true,
        }
    }
}

impl PanelVisibility {
    /// The embed layout: map, plots and the time bar; the side panels closed.
    pub fn embedded() -> Self {
        Self {
            parameters: false,
            explanation: false,
            plots: true,
        }
    }
}
