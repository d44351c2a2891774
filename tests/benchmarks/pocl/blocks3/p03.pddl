; Sussman's anomaly next to a separate tower of two to swap.
(define (problem sussman-and-a-swap)
  (:domain blocks3)
  (:objects a b c d e - block)
  (:init (ontable a) (on c a) (clear c) (ontable b) (clear b) (ontable d) (on e d) (clear e))
  (:goal (and (on a b) (on b c) (on d e))))
