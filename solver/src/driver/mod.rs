//! Running a case: the engine (state and buffers, one step), a short calibration of its step, the loop over output times with its observers, the output files, and numbers in words for people.

pub mod calibrate;
pub mod checkpoint;
pub mod dispatch;
pub mod engine;
pub mod guard;
pub mod output;
pub mod run;
pub mod traffic;
pub mod units;
