//! Where a run's Rerun stream goes: `--rerun off|save[:PATH]|spawn|connect[:URL]`,
//! and how often it logs: `--rerun-rate phase|step|<N>`.

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

/// The gRPC address `connect` uses when none is given (the viewer's default
/// port on this machine).
pub const DEFAULT_CONNECT_URL: &str = "rerun+http://127.0.0.1:9876/proxy";

/// Where the stream goes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RerunSink {
    /// nothing is logged
    Off,
    /// an `.rrd` file; `None`: the command's default file name
    Save(Option<PathBuf>),
    /// a viewer started from `rerun` on PATH (or one already listening)
    Spawn,
    /// a running viewer or server at this gRPC URL
    Connect(String),
}

/// A `--rerun` or `--rerun-rate` value that cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SinkParseError {
    /// Not one of the sink kinds.
    #[error("unknown Rerun sink {0:?}: expected off, save[:PATH], spawn or connect[:URL]")]
    Unknown(String),
    /// `save:` with nothing after the colon.
    #[error("Rerun sink {0:?} names no file: write save:PATH, or save for the default file")]
    EmptyPath(String),
    /// `spawn` and `off` take no argument.
    #[error("Rerun sink {0:?} takes no argument")]
    UnexpectedArgument(String),
    /// The URL is not a Rerun gRPC proxy address.
    #[error(
        "Rerun URL {0:?} is not a gRPC proxy address: expected rerun+http://HOST:PORT/proxy or HOST:PORT"
    )]
    BadUrl(String),
    /// Not a logging rate.
    #[error(
        "unknown Rerun logging rate {0:?}: expected phase (once per phase), step (every physics step) or a number of steps (1-180)"
    )]
    BadRate(String),
}

impl FromStr for RerunSink {
    type Err = SinkParseError;

    fn from_str(input: &str) -> Result<Self, Self::Err> {
        let (kind, arg) = match input.split_once(':') {
            Some((k, a)) => (k, Some(a)),
            None => (input, None),
        };
        match (kind, arg) {
            ("off", None) => Ok(Self::Off),
            ("spawn", None) => Ok(Self::Spawn),
            ("off" | "spawn", Some(_)) => Err(SinkParseError::UnexpectedArgument(input.into())),
            ("save", None) => Ok(Self::Save(None)),
            ("save", Some("")) => Err(SinkParseError::EmptyPath(input.into())),
            ("save", Some(path)) => Ok(Self::Save(Some(PathBuf::from(path)))),
            ("connect", None) => Ok(Self::Connect(DEFAULT_CONNECT_URL.into())),
            ("connect", Some(url)) => normalise_url(url)
                .map(Self::Connect)
                .ok_or_else(|| SinkParseError::BadUrl(url.into())),
            _ => Err(SinkParseError::Unknown(input.into())),
        }
    }
}

impl fmt::Display for RerunSink {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Off => write!(f, "off"),
            Self::Save(None) => write!(f, "save"),
            Self::Save(Some(p)) => write!(f, "save:{}", p.display()),
            Self::Spawn => write!(f, "spawn"),
            Self::Connect(url) => write!(f, "connect:{url}"),
        }
    }
}

/// `HOST:PORT` becomes `rerun+http://HOST:PORT/proxy`; a full
/// `rerun+http(s)://HOST:PORT/proxy` URL is kept. `None` if neither.
fn normalise_url(url: &str) -> Option<String> {
    let full = if url.contains("://") {
        url.to_string()
    } else {
        format!("rerun+http://{url}/proxy")
    };
    let rest = full
        .strip_prefix("rerun+http://")
        .or_else(|| full.strip_prefix("rerun+https://"))?;
    let authority = rest.strip_suffix("/proxy")?;
    let (host, port) = authority.rsplit_once(':')?;
    if host.is_empty() || port.parse::<u16>().is_err() {
        return None;
    }
    Some(full)
}

/// How often a rollout logs the robot, tiles, contacts and scalars.
/// Curves and rewards are logged once per phase whatever the rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LogRate {
    /// once per phase, at its end (the default: the cheapest)
    #[default]
    PerPhase,
    /// every `n` physics steps, and at the phase end
    EverySteps(usize),
}

impl LogRate {
    /// Whether physics step `step_in_phase` (1-based) of a phase of `steps`
    /// steps is logged.
    pub fn logs_step(&self, step_in_phase: usize, steps: usize) -> bool {
        match *self {
            Self::PerPhase => step_in_phase == steps,
            Self::EverySteps(n) => step_in_phase.is_multiple_of(n) || step_in_phase == steps,
        }
    }

    /// Frames logged by a phase of `steps` steps that runs to its end.
    pub fn frames_per_phase(&self, steps: usize) -> usize {
        (1..=steps).filter(|&i| self.logs_step(i, steps)).count()
    }
}

impl FromStr for LogRate {
    type Err = SinkParseError;

    fn from_str(input: &str) -> Result<Self, Self::Err> {
        match input {
            "phase" => Ok(Self::PerPhase),
            "step" => Ok(Self::EverySteps(1)),
            n => match n.parse::<usize>() {
                Ok(n) if (1..=robot::action::SAMPLES_PER_PHASE).contains(&n) => {
                    Ok(Self::EverySteps(n))
                }
                _ => Err(SinkParseError::BadRate(input.into())),
            },
        }
    }
}

impl fmt::Display for LogRate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::PerPhase => write!(f, "phase"),
            Self::EverySteps(1) => write!(f, "step"),
            Self::EverySteps(n) => write!(f, "{n}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sinks_parse_and_print_back() {
        for s in [
            "off",
            "save",
            "save:/tmp/a.rrd",
            "spawn",
            "connect:rerun+http://127.0.0.1:9876/proxy",
        ] {
            let sink: RerunSink = s.parse().unwrap();
            assert_eq!(sink.to_string(), s);
        }
        assert_eq!(
            "connect".parse::<RerunSink>().unwrap(),
            RerunSink::Connect(DEFAULT_CONNECT_URL.into())
        );
        assert_eq!(
            "connect:localhost:9000".parse::<RerunSink>().unwrap(),
            RerunSink::Connect("rerun+http://localhost:9000/proxy".into())
        );
    }

    #[test]
    fn bad_sinks_say_what_is_wrong() {
        let err = |s: &str| s.parse::<RerunSink>().unwrap_err().to_string();
        assert!(err("svae").contains("unknown Rerun sink \"svae\""));
        assert!(err("save:").contains("names no file"));
        assert!(err("spawn:x").contains("takes no argument"));
        assert!(err("connect:nowhere").contains("not a gRPC proxy address"));
        assert!(err("connect:host:99999").contains("not a gRPC proxy address"));
        assert!(err("connect:http://h:1/x").contains("not a gRPC proxy address"));
    }

    #[test]
    fn rates_count_frames() {
        assert_eq!(LogRate::PerPhase.frames_per_phase(180), 1);
        assert_eq!(
            "step".parse::<LogRate>().unwrap().frames_per_phase(180),
            180
        );
        assert_eq!("45".parse::<LogRate>().unwrap().frames_per_phase(180), 4);
        // 7 does not divide 180: the phase end is logged too.
        assert_eq!("7".parse::<LogRate>().unwrap().frames_per_phase(180), 26);
        assert!("0".parse::<LogRate>().is_err());
        assert!("181".parse::<LogRate>().is_err());
        assert!("fast".parse::<LogRate>().is_err());
    }
}
