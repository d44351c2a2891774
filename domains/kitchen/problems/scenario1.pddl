; Scenario 1 (Sec. 5.5, Fig. 5.11): from its start pose the B21 carries one cup from table1 to table2.
(define (problem scenario1)
  (:domain kitchen)
  (:objects start table1 table2 - location
            cup1 - cup)
  (:init (robot start) (table table1) (table table2) (on cup1 table1) (handempty))
  (:goal (on cup1 table2)))
