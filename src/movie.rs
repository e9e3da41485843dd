//! Movies: frames encoded as they are rendered, through `ffmpeg`, with
//! resume.
//!
//! The model:
//!
//! - A movie's output names its container: `.mp4` (H.264), `.webm` (VP9) or
//!   `.gif` (a palette made from the frames). [`check_encoder`] finds
//!   `ffmpeg` on `PATH` before any work, or says which package to install
//!   (and that numbered PNGs need no encoder).
//! - Every frame is also kept as a PNG in a directory beside the movie,
//!   `NAME.frames/` ([`MovieFrames`]), with a stamp of what is rendered
//!   (the scene, the frame list, the size): a run that stops partway
//!   restarts from the frames already there when the stamp is the same,
//!   and starts over (saying so) when it is not. The directory is removed
//!   once the movie is written, unless asked to keep it.
//! - [`Encoder`] pipes raw RGB frames, in order, into one `ffmpeg` process
//!   writing a temporary file in the frame directory, renamed into place when
//!   `ffmpeg` succeeds: an interrupted or failed encode never leaves a
//!   partial movie or destroys an old one.
//! - `quality` 1–100 (default 80) maps to the codec's constant-quality
//!   setting (H.264 CRF 42 − 0.3·q: 18 at 80; VP9 CRF 63 − 0.45·q: 27 at
//!   80); GIFs are palette-limited and take no quality.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};

use crate::SceneError;

/// The containers a movie can be written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MovieFormat {
    Mp4,
    Webm,
    Gif,
}

impl MovieFormat {
    /// The format `path`'s extension names (case-insensitive), if a movie.
    pub fn of(path: &Path) -> Option<MovieFormat> {
        let e = path.extension()?.to_string_lossy().to_ascii_lowercase();
        match e.as_str() {
            "mp4" => Some(MovieFormat::Mp4),
            "webm" => Some(MovieFormat::Webm),
            "gif" => Some(MovieFormat::Gif),
            _ => None,
        }
    }

    /// ffmpeg's muxer name.
    fn muxer(self) -> &'static str {
        match self {
            MovieFormat::Mp4 => "mp4",
            MovieFormat::Webm => "webm",
            MovieFormat::Gif => "gif",
        }
    }
}

/// Frame rate and quality of a movie.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MovieSettings {
    /// Frames per second, > 0 (default 24).
    pub fps: f64,
    /// 1–100 (default 80).
    pub quality: u32,
}

impl Default for MovieSettings {
    fn default() -> Self {
        MovieSettings {
            fps: 24.0,
            quality: 80,
        }
    }
}

impl MovieSettings {
    /// Refuses a frame rate that is not finite and positive (or above
    /// 1000) and a quality outside 1–100.
    pub fn check(&self) -> Result<(), SceneError> {
        if !(self.fps.is_finite() && self.fps > 0.0 && self.fps <= 1000.0) {
            return Err(SceneError::setting(
                "fps",
                format!("{} is not a frame rate in (0, 1000]", self.fps),
            ));
        }
        if !(1..=100).contains(&self.quality) {
            return Err(SceneError::setting(
                "quality",
                format!("{} is outside 1..=100", self.quality),
            ));
        }
        Ok(())
    }
}

/// The encoder program: `VOXLESS_FFMPEG` when set, else `ffmpeg` on PATH.
fn ffmpeg() -> String {
    std::env::var("VOXLESS_FFMPEG").unwrap_or_else(|_| "ffmpeg".into())
}

/// Checks that `ffmpeg` runs, before any rendering: else an error naming the
/// package to install and the numbered-PNG alternative.
pub fn check_encoder(output: &Path) -> Result<(), SceneError> {
    let ok = Command::new(ffmpeg())
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if ok {
        return Ok(());
    }
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "frame".into());
    Err(SceneError::setting(
        "output",
        format!(
            "{} is a movie, which is encoded by ffmpeg, and ffmpeg was not found on PATH: \
             install it (Debian/Ubuntu: apt install ffmpeg; macOS: brew install ffmpeg; conda: \
             conda install ffmpeg), or write numbered images with -o {stem}.png",
            output.display()
        ),
    ))
}

/// The frames of a movie kept on disk for resume (see the module docs).
pub struct MovieFrames {
    dir: PathBuf,
    count: usize,
}

impl MovieFrames {
    /// The frame directory of `output` (`NAME.frames` beside it) for
    /// `count` frames of what `stamp` describes: created, or reused when
    /// its stamp is `stamp` (else emptied, with a note in `notes`).
    pub fn open(
        output: &Path,
        count: usize,
        stamp: &str,
        notes: &mut Vec<String>,
    ) -> Result<MovieFrames, SceneError> {
        let dir = frames_dir(output);
        let stamp_file = dir.join("stamp.json");
        let io = |e: std::io::Error| SceneError::output(&dir, e.to_string());
        if dir.is_dir() {
            let same = std::fs::read_to_string(&stamp_file).is_ok_and(|s| s == stamp);
            if !same {
                notes.push(format!(
                    "{} holds frames of another movie (a different scene, frames or size): \
                     starting over",
                    dir.display()
                ));
                std::fs::remove_dir_all(&dir).map_err(io)?;
            }
        }
        std::fs::create_dir_all(&dir).map_err(io)?;
        std::fs::write(&stamp_file, stamp).map_err(io)?;
        let frames = MovieFrames { dir, count };
        let done = (0..count).filter(|&k| frames.has(k)).count();
        if done > 0 {
            notes.push(format!(
                "resuming: {done} of {count} frames are already in {}",
                frames.dir.display()
            ));
        }
        Ok(frames)
    }

    /// The PNG of frame `k` (0-based in the movie).
    pub fn path(&self, k: usize) -> PathBuf {
        self.dir.join(format!("frame_{k:06}.png"))
    }

    /// Whether frame `k` is on disk (written whole: frames are renamed into
    /// place).
    pub fn has(&self, k: usize) -> bool {
        k < self.count && self.path(k).is_file()
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Removes the directory (once the movie is written).
    pub fn remove(self) -> Result<(), SceneError> {
        std::fs::remove_dir_all(&self.dir).map_err(|e| SceneError::output(&self.dir, e.to_string()))
    }
}

/// `NAME.frames` beside `output`.
pub fn frames_dir(output: &Path) -> PathBuf {
    let name = output
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    output.with_file_name(format!("{name}.frames"))
}

/// An `ffmpeg` process encoding frames piped to it (see the module docs).
pub struct Encoder {
    child: Child,
    stdin: Option<ChildStdin>,
    output: PathBuf,
    partial: PathBuf,
    log: PathBuf,
    size: (u32, u32),
    frames: usize,
}

impl Encoder {
    /// Starts encoding `w`×`h` frames into `output` (its format by its
    /// extension), with its partial file and ffmpeg's log in `scratch` (an
    /// interrupted encode leaves them there, not beside the output). Odd
    /// sizes are padded by a black row or column for the codecs that need
    /// even ones (H.264, VP9), with a note in `notes`.
    pub fn start(
        output: &Path,
        scratch: &Path,
        (w, h): (u32, u32),
        settings: &MovieSettings,
        notes: &mut Vec<String>,
    ) -> Result<Encoder, SceneError> {
        settings.check()?;
        let format = MovieFormat::of(output).ok_or_else(|| {
            SceneError::setting(
                "output",
                format!("{}: a movie is .mp4, .webm or .gif", output.display()),
            )
        })?;
        let partial = scratch.join("partial");
        let log = scratch.join("ffmpeg.log");
        let q = settings.quality as f64;
        let mut args: Vec<String> = [
            "-y",
            "-hide_banner",
            "-loglevel",
            "error",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-s",
            &format!("{w}x{h}"),
            "-framerate",
            &format!("{}", settings.fps),
            "-i",
            "-",
        ]
        .map(String::from)
        .to_vec();
        let even = (w % 2 == 1 || h % 2 == 1) && format != MovieFormat::Gif;
        if even {
            notes.push(format!(
                "{}: H.264 and VP9 need even sizes: {w}×{h} is padded to {}×{} with black",
                output.display(),
                w + w % 2,
                h + h % 2
            ));
        }
        let pad = "pad=ceil(iw/2)*2:ceil(ih/2)*2";
        let codec: Vec<String> = match format {
            MovieFormat::Mp4 => vec![
                "-c:v".into(),
                "libx264".into(),
                "-preset".into(),
                "medium".into(),
                "-crf".into(),
                format!("{}", (42.0 - 0.3 * q).round()),
                "-pix_fmt".into(),
                "yuv420p".into(),
                "-movflags".into(),
                "+faststart".into(),
            ],
            MovieFormat::Webm => vec![
                "-c:v".into(),
                "libvpx-vp9".into(),
                "-crf".into(),
                format!("{}", (63.0 - 0.45 * q).round()),
                "-b:v".into(),
                "0".into(),
                "-row-mt".into(),
                "1".into(),
                "-deadline".into(),
                "good".into(),
                "-cpu-used".into(),
                "4".into(),
                "-pix_fmt".into(),
                "yuv420p".into(),
            ],
            MovieFormat::Gif => vec![
                "-vf".into(),
                "split[a][b];[a]palettegen[p];[b][p]paletteuse".into(),
            ],
        };
        if even {
            args.extend(["-vf".into(), pad.into()]);
        }
        args.extend(codec);
        args.extend(["-f".into(), format.muxer().into()]);
        args.push(partial.to_string_lossy().into_owned());
        let log_file =
            std::fs::File::create(&log).map_err(|e| SceneError::output(&log, e.to_string()))?;
        let mut child = Command::new(ffmpeg())
            .args(&args)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(log_file)
            .spawn()
            .map_err(|e| SceneError::setting("output", format!("ffmpeg did not start: {e}")))?;
        let stdin = child.stdin.take();
        Ok(Encoder {
            child,
            stdin,
            output: output.to_path_buf(),
            partial,
            log,
            size: (w, h),
            frames: 0,
        })
    }

    /// Encodes the next frame: `rgb` is `w`×`h` 8-bit sRGB, row 0 at the
    /// top.
    pub fn push(&mut self, rgb: &[u8]) -> Result<(), SceneError> {
        let (w, h) = self.size;
        if rgb.len() != (w * h * 3) as usize {
            return Err(SceneError::setting(
                "movie",
                format!(
                    "frame {} is {} bytes, not the {w}×{h}×3 of the movie",
                    self.frames,
                    rgb.len()
                ),
            ));
        }
        let written = match &mut self.stdin {
            Some(s) => s.write_all(rgb),
            None => Err(std::io::Error::other("closed")),
        };
        if written.is_err() {
            // ffmpeg stopped: its log says why.
            let _ = self.child.wait();
            return Err(self.failure());
        }
        self.frames += 1;
        Ok(())
    }

    /// Ends the stream, waits for ffmpeg and puts the movie in place.
    /// Returns the number of frames encoded.
    pub fn finish(mut self) -> Result<usize, SceneError> {
        drop(self.stdin.take());
        let status = self
            .child
            .wait()
            .map_err(|e| SceneError::setting("movie", format!("ffmpeg: {e}")))?;
        if !status.success() {
            return Err(self.failure());
        }
        std::fs::rename(&self.partial, &self.output)
            .map_err(|e| SceneError::output(&self.output, e.to_string()))?;
        let _ = std::fs::remove_file(&self.log);
        Ok(self.frames)
    }

    /// The error of a failed encode: the end of ffmpeg's log.
    fn failure(&self) -> SceneError {
        let log = std::fs::read_to_string(&self.log).unwrap_or_default();
        let tail: Vec<&str> = log.lines().rev().take(4).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        let _ = std::fs::remove_file(&self.partial);
        SceneError::setting(
            "movie",
            format!(
                "ffmpeg failed to encode {}: {}",
                self.output.display(),
                if tail.is_empty() {
                    "it stopped without a message".to_string()
                } else {
                    tail.join(" / ")
                }
            ),
        )
    }
}

impl Drop for Encoder {
    /// An encode dropped before [`Encoder::finish`] (an error, an
    /// interrupt) leaves no partial file.
    fn drop(&mut self) {
        if self.stdin.is_some() {
            drop(self.stdin.take());
            let _ = self.child.kill();
            let _ = self.child.wait();
            let _ = std::fs::remove_file(&self.partial);
            let _ = std::fs::remove_file(&self.log);
        }
    }
}

/// What a movie's frames depend on — the scene, the (path frame, data
/// frame) list and the size — as the stamp [`MovieFrames::open`] compares:
/// an interrupted movie resumes only when it is unchanged.
pub fn stamp(
    desc: &voxless_scene::SceneDesc,
    frames: &[(usize, usize)],
    size: (u32, u32),
) -> String {
    let scene = crate::scene_toml(desc).unwrap_or_else(|_| format!("{desc:?}"));
    format!(
        "{{\"size\": [{}, {}], \"frames\": {frames:?}}}\n{scene}",
        size.0, size.1
    )
}

/// A movie being written: frames kept for resume ([`MovieFrames`]) and
/// encoded in order ([`Encoder`]). Front-ends render frame `k` only when
/// [`MovieWriter::has`] says it is not on disk, and hand every frame over
/// in order.
pub struct MovieWriter {
    frames: MovieFrames,
    encoder: Encoder,
    keep: bool,
    next: usize,
}

impl MovieWriter {
    /// Starts `output` (`count` frames of `size`, what `stamp` describes;
    /// see [`MovieFrames::open`]), keeping the frame PNGs after encoding
    /// when `keep`.
    pub fn start(
        output: &Path,
        count: usize,
        stamp: &str,
        size: (u32, u32),
        settings: &MovieSettings,
        keep: bool,
        notes: &mut Vec<String>,
    ) -> Result<MovieWriter, SceneError> {
        check_encoder(output)?;
        let frames = MovieFrames::open(output, count, stamp, notes)?;
        let encoder = Encoder::start(output, frames.dir(), size, settings, notes)?;
        Ok(MovieWriter {
            frames,
            encoder,
            keep,
            next: 0,
        })
    }

    /// Whether frame `k` is on disk from an earlier run.
    pub fn has(&self, k: usize) -> bool {
        self.frames.has(k)
    }

    /// Frame `k`, in order: the image given (saved for resume, then
    /// encoded), or, with `None`, the frame on disk.
    pub fn put(&mut self, k: usize, rgb: Option<&[u8]>) -> Result<(), SceneError> {
        if k != self.next {
            return Err(SceneError::setting(
                "movie",
                format!("frame {k} came before frame {}", self.next),
            ));
        }
        let path = self.frames.path(k);
        let (w, h) = self.encoder.size;
        let bytes = match rgb {
            Some(rgb) => {
                voxless_io::write_png_rgb8(&path, w, h, rgb)?;
                std::borrow::Cow::Borrowed(rgb)
            }
            None => {
                let (pw, ph, rgb) = voxless_io::read_png_rgb8(&path)?;
                if (pw, ph) != (w, h) {
                    return Err(SceneError::setting(
                        "movie",
                        format!("{} is {pw}×{ph}, not {w}×{h}", path.display()),
                    ));
                }
                std::borrow::Cow::Owned(rgb)
            }
        };
        self.encoder.push(&bytes)?;
        self.next += 1;
        Ok(())
    }

    /// Finishes the movie; removes the frame PNGs unless kept. Returns the
    /// frames encoded and, when kept, where the PNGs are.
    pub fn finish(self) -> Result<(usize, Option<PathBuf>), SceneError> {
        let n = self.encoder.finish()?;
        if self.keep {
            Ok((n, Some(self.frames.dir().to_path_buf())))
        } else {
            self.frames.remove()?;
            Ok((n, None))
        }
    }
}
