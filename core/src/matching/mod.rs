//! Brute-force matching and the lab's strategies (being written).
