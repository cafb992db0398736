//! One step of an mms mouse: the referee's translation of its command lines.

use super::{Session, Verdict, failure, write_failure};
use crate::engine::game::Sense;
use crate::runner::outcome::MatchStatus;

impl Session {
    /// Plays one step with an mms mouse (docs/PROTOCOL-mms.md): the translator `mouse`
    /// answers the mouse's commands (written back within the step's limit) until one of
    /// them is the step's action. The whole conversation is the step's answer time.
    pub async fn exchange_mms(
        &mut self,
        sense: &Sense,
        mouse: &mut crate::protocol::mms::Mouse,
    ) -> Verdict {
        use crate::protocol::mms::Next;
        let mut ask = self.ask(sense).await;
        let mms_fault = |e: crate::protocol::mms::MmsError| {
            Verdict::Fault(MatchStatus::ProtocolError, failure(e.0, sense.step))
        };
        let mut next = match mouse.begin(sense) {
            Ok(n) => n,
            Err(e) => return mms_fault(e),
        };
        loop {
            next = match next {
                Next::Act(action) => {
                    return match self.answered(&ask) {
                        Ok((answer_us, cpu_us)) => Verdict::Answer {
                            action,
                            answer_us,
                            cpu_us,
                            debug: None,
                        },
                        Err(verdict) => *verdict,
                    };
                }
                Next::Write(mut text) => {
                    text.push('\n');
                    if let Err(e) = self.send_sense(text.as_bytes(), ask.deadline).await {
                        let (status, failure) = write_failure(e, sense.step);
                        return self.limit_or(Verdict::Fault(status, failure), sense.step);
                    }
                    Next::Read
                }
                Next::Read => {
                    if let Err(verdict) = self.wait_line(&mut ask).await {
                        return *verdict;
                    }
                    let line = self.replies.line();
                    self.stderr
                        .meter
                        .add(line.len() as u64 + crate::runner::flood::MMS_LINE_WEIGHT);
                    let text = String::from_utf8_lossy(line);
                    match mouse.line(text.trim_end_matches('\r')) {
                        Ok(n) => n,
                        Err(e) => return mms_fault(e),
                    }
                }
            };
        }
    }
}
