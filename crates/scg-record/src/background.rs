//! Writing recordings on a background thread, so encoding and compression overlap the
//! simulation instead of stopping it.

use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use scg_core::frame::{Frame, FrameSink, WearMap};

/// What the writer thread is handed.
enum Msg {
    Frame(Arc<Frame>),
    Wear(WearMap),
}

/// Frames waiting for the writer at most (back-pressure beyond that).
const QUEUE: usize = 2;

/// A [`FrameSink`] that hands frames to a writer thread owning the real sinks.
///
/// `write_shared` queues the frame itself (`write_frame` a copy) and returns; an error of a sink surfaces
/// at the next `write_frame` or at `finish`, which closes the queue, waits for the writer
/// and finishes every sink (so the files are complete when it returns).
pub struct Background {
    tx: Option<SyncSender<Msg>>,
    writer: Option<JoinHandle<Result<(), String>>>,
    error: Arc<Mutex<Option<String>>>,
}

fn writer(
    rx: Receiver<Msg>,
    mut sinks: Vec<Box<dyn FrameSink>>,
    error: Arc<Mutex<Option<String>>>,
) -> Result<(), String> {
    let mut first: Option<String> = None;
    for msg in rx {
        if first.is_some() {
            continue; // drain so the sender never blocks
        }
        for s in sinks.iter_mut() {
            let written = match &msg {
                Msg::Frame(frame) => s.write_frame(frame),
                Msg::Wear(wear) => s.write_wear(wear),
            };
            if let Err(e) = written {
                if let Ok(mut slot) = error.lock() {
                    *slot = Some(e.clone());
                }
                first = Some(e);
                break;
            }
        }
    }
    for s in sinks.iter_mut() {
        if let Err(e) = s.finish() {
            first.get_or_insert(e);
        }
    }
    first.map_or(Ok(()), Err)
}

impl Background {
    /// Start the writer thread for `sinks`.
    pub fn spawn(sinks: Vec<Box<dyn FrameSink>>) -> Self {
        let (tx, rx) = sync_channel(QUEUE);
        let error = Arc::new(Mutex::new(None));
        let e2 = Arc::clone(&error);
        let writer = std::thread::Builder::new()
            .name("scg-recorder".into())
            .spawn(move || writer(rx, sinks, e2))
            .ok();
        Background {
            tx: Some(tx),
            writer,
            error,
        }
    }
}

impl Background {
    fn send(&mut self, msg: Msg) -> Result<(), String> {
        if let Some(e) = self.error.lock().map_err(|e| e.to_string())?.clone() {
            return Err(e);
        }
        let tx = self.tx.as_ref().ok_or("recorder already finished")?;
        if self.writer.is_none() {
            return Err("could not start the recorder thread".into());
        }
        tx.send(msg)
            .map_err(|_| "the recorder thread stopped".to_string())
    }
}

impl FrameSink for Background {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), String> {
        self.send(Msg::Frame(Arc::new(frame.clone())))
    }

    fn write_shared(&mut self, frame: &Arc<Frame>) -> Result<(), String> {
        self.send(Msg::Frame(Arc::clone(frame)))
    }

    fn write_wear(&mut self, wear: &WearMap) -> Result<(), String> {
        self.send(Msg::Wear(wear.clone()))
    }

    fn finish(&mut self) -> Result<(), String> {
        self.tx = None; // closes the queue
        match self.writer.take() {
            Some(h) => h
                .join()
                .map_err(|_| "the recorder thread panicked".to_string())?,
            None => Ok(()),
        }
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        let _ = self.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scg_core::frame::MemorySink;

    struct Failing;
    impl FrameSink for Failing {
        fn write_frame(&mut self, _: &Frame) -> Result<(), String> {
            Err("disk full".into())
        }
        fn finish(&mut self) -> Result<(), String> {
            Ok(())
        }
    }

    #[test]
    fn frames_arrive_in_order_and_finish_waits() {
        let mem = MemorySink::default();
        let frames = mem.frames.clone();
        let mut bg = Background::spawn(vec![Box::new(mem)]);
        for step in 0..20 {
            bg.write_frame(&Frame {
                step,
                ..Default::default()
            })
            .unwrap();
        }
        bg.finish().unwrap();
        let got: Vec<u64> = frames.lock().unwrap().iter().map(|f| f.step).collect();
        assert_eq!(got, (0..20).collect::<Vec<_>>());
    }

    #[test]
    fn errors_surface() {
        let mut bg = Background::spawn(vec![Box::new(Failing)]);
        let mut failed = false;
        for _ in 0..10 {
            if bg.write_frame(&Frame::default()).is_err() {
                failed = true;
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        assert!(failed || bg.finish().is_err());
    }
}
