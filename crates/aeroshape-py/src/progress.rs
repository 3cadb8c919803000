//! Progress of a long computation, reported while the GIL is released: to the caller's
//! callback `progress(phase, done, total)`, or else as DEBUG records of the `logging` logger
//! `"aeroshape"`. Nothing is printed. A callback that raises is not called again; its
//! exception is raised when the computation ends.

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;

/// The name of the package's logger.
pub const LOGGER: &str = "aeroshape";

/// `logging.DEBUG`, `INFO`, `WARNING` (fixed by the `logging` module).
pub const DEBUG: u8 = 10;
/// `logging.INFO`.
pub const INFO: u8 = 20;
/// `logging.WARNING`.
pub const WARNING: u8 = 30;

/// The logger, fetched once (an import per call costs tens of microseconds).
static THE_LOGGER: PyOnceLock<Py<PyAny>> = PyOnceLock::new();

/// Where the progress of one computation goes; see the module doc.
pub struct Progress {
    task: &'static str,
    callback: Option<Py<PyAny>>,
    logger: Option<Py<PyAny>>,
    error: Option<PyErr>,
}

impl Progress {
    /// Progress of `task` (e.g. `"evaluate"`) to `callback`, or to the logger when it is
    /// `None` and the logger is enabled for DEBUG (otherwise nowhere, at no cost).
    pub fn new(
        py: Python<'_>,
        task: &'static str,
        callback: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let logger = match &callback {
            Some(_) => None,
            None => enabled_logger(py, DEBUG)?,
        };
        Ok(Self {
            task,
            callback: callback.map(Bound::unbind),
            logger,
            error: None,
        })
    }

    /// Reports that `phase` started (`done` of `total` steps finished); takes the GIL for the
    /// call only.
    pub fn report(&mut self, phase: &str, done: usize, total: usize) {
        if self.error.is_some() || (self.callback.is_none() && self.logger.is_none()) {
            return;
        }
        Python::attach(|py| {
            let r = match (&self.callback, &self.logger) {
                (Some(cb), _) => cb.call1(py, (phase, done, total)).map(drop),
                (None, Some(log)) => log
                    .call_method1(
                        py,
                        "debug",
                        (format!("{}: {phase} ({done}/{total})", self.task),),
                    )
                    .map(drop),
                (None, None) => Ok(()),
            };
            if let Err(e) = r {
                self.error = Some(e);
            }
        });
    }

    /// The callback's exception, if it raised.
    pub fn finish(self) -> PyResult<()> {
        self.error.map_or(Ok(()), Err)
    }
}

/// The logger `"aeroshape"` if it is enabled for `level` ([`DEBUG`], [`INFO`], [`WARNING`]).
fn enabled_logger(py: Python<'_>, level: u8) -> PyResult<Option<Py<PyAny>>> {
    let logger = THE_LOGGER.get_or_try_init(py, || {
        py.import("logging")?
            .call_method1("getLogger", (LOGGER,))
            .map(Bound::unbind)
    })?;
    let on: bool = logger
        .call_method1(py, "isEnabledFor", (level,))?
        .extract(py)?;
    Ok(on.then(|| logger.clone_ref(py)))
}

/// Logs `message` to the logger `"aeroshape"` at `level` ([`INFO`], [`WARNING`], ...).
pub fn log(py: Python<'_>, level: u8, message: impl FnOnce() -> String) -> PyResult<()> {
    if let Some(logger) = enabled_logger(py, level)? {
        logger.call_method1(py, "log", (level, message()))?;
    }
    Ok(())
}
