//! Scenes: the tool and the plies to drape on it.
